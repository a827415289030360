"""docs/API.md, the own-task API's reference, generated from the docstrings and signatures of what a user imports:

    python -m connrl.own.reference > docs/API.md

(a test keeps docs/API.md current). The docstrings are the reference: a change to one shows in the diff of API.md.
"""

from __future__ import annotations

import inspect

from connrl.own import api, callbacks, plots, tune

# (section, object, the name a user writes)
ENTRIES = (
    ("Agents", api.make_agent, "connrl.make_agent"),
    ("Agents", api.load, "connrl.load"),
    ("Agents", api.evaluate, "connrl.evaluate"),
    ("Agents", api.record_lessons, "connrl.record_lessons"),
    ("Agents", api.Agent, "connrl.Agent"),
    ("Agents", api.AgentOptions, "connrl.AgentOptions"),
    ("Callbacks", callbacks.Callback, "connrl.own.callbacks.Callback"),
    ("Callbacks", callbacks.EvalCallback, "connrl.own.callbacks.EvalCallback"),
    ("Callbacks", callbacks.CheckpointCallback, "connrl.own.callbacks.CheckpointCallback"),
    ("Callbacks", callbacks.ProgressLog, "connrl.own.callbacks.ProgressLog"),
    ("Callbacks", callbacks.TensorBoardLog, "connrl.own.callbacks.TensorBoardLog"),
    ("Callbacks", callbacks.read_progress, "connrl.own.callbacks.read_progress"),
    ("Curves", plots.write_runs_curve, "connrl.own.plots.write_runs_curve"),
    ("Search", tune.run_search, "connrl.own.tune.run_search"),
    ("Search", tune.planned, "connrl.own.tune.planned"),
)
AGENT_METHODS = ("learn", "predict", "evaluate", "save", "divergence", "temperature", "learning_rate", "check_env")


def _doc(obj) -> str:
    return inspect.cleandoc(obj.__doc__ or "(no docstring)")


def _signature(obj) -> str:
    try:
        return str(inspect.signature(obj, eval_str=True))  # annotations as types, not the strings the source holds
    except (TypeError, ValueError, NameError):
        return str(inspect.signature(obj))


def reference() -> str:
    """The reference as Markdown."""
    lines = ["# connrl API reference (own tasks)", "",
             "Generated from the docstrings by `python -m connrl.own.reference > docs/API.md`; README's \"Your own "
             "task\" shows the workflow, docs/ARCHITECTURE.md the code's layout.", ""]
    section = None
    for where, obj, name in ENTRIES:
        if where != section:
            lines += [f"## {where}", ""]
            section = where
        lines += [f"### `{name}{_signature(obj)}`", "", _doc(obj), ""]
        if obj is api.Agent:
            for method in AGENT_METHODS:
                fn = getattr(api.Agent, method)
                lines += [f"#### `Agent.{method}{_signature(fn)}`", "", _doc(fn), ""]
    return "\n".join(lines).rstrip("\n") + "\n"


if __name__ == "__main__":
    print(reference(), end="")
