"""The registry finds every experiment module by itself: a module of connrl/experiments that assigns EXPERIMENTS
(read here from the source, not by the registry's own means) is found, with its CHAPTER, and nothing else."""

import ast
from pathlib import Path

from connrl.experiments import registry

FOLDER = Path(registry.__file__).parent


def _declared() -> dict[str, int]:
    out = {}
    for path in sorted(FOLDER.glob("*.py")):
        body = ast.parse(path.read_text()).body
        names = {t.id: node.value for node in body if isinstance(node, ast.Assign) for t in node.targets
                 if isinstance(t, ast.Name)}
        if "EXPERIMENTS" in names:
            out[f"connrl.experiments.{path.stem}"] = ast.literal_eval(names["CHAPTER"])
    return out


def test_every_module_that_defines_experiments_is_found_with_its_chapter():
    declared = _declared()
    assert len(declared) == 13
    assert {m.__name__: m.CHAPTER for m in registry.spec_modules()} == declared
    assert [m.CHAPTER for m in registry.spec_modules()] == sorted(declared.values())  # chapter by chapter
    assert registry.chapters() == sorted(set(declared.values()))


def test_the_chapters_partition_the_experiments():
    every = registry.all_experiments()
    by = [s.name for c in registry.chapters() for s in registry.by_chapter([c])]
    assert sorted(by) == sorted(every) and len(by) == len(set(by)) == 51
    assert {s.name for s in registry.by_chapter([8])} == {"integration", "integration-fresh", "steps-to-learn"}
