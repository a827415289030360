"""Issue 24: every size-like parameter has an upper bound, checked before any run (connrl.experiments.spec.CAPS,
MAX_COUNT), and every registered experiment's profiles and variants stay well within them."""

import dataclasses

import pytest

from connrl import cli
from connrl.experiments.behaviours import TrainingPlan
from connrl.experiments.registry import all_experiments
from connrl.experiments.spec import CAPS, cap, field_kinds, override
from connrl.experiments.sweep import sweep_spec
from connrl.experiments.td_depth import DepthParams

SPECS = all_experiments()  # every spec checks its profiles and variants when built: building them is a test


def _refused(name: str, setting: str, tmp_path, monkeypatch) -> str:
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "execute_job", lambda job: pytest.fail("a run started"))
    with pytest.raises(SystemExit) as e:
        cli.main(["sweep", name, "--set", setting, "--seeds", "0:1", "--out", str(tmp_path), "--workers", "1"])
    text = str(e.value.code)
    assert text.startswith("connrl: ") and "\n" not in text and "Traceback" not in text, text
    assert not any(tmp_path.iterdir())
    return text


@pytest.mark.parametrize("name, setting, message", [
    ("pole-full", "max_trials=1e23", "parameter max_trials must be a whole number in [1, 1000000], got 1e+23"),
    ("pole-full", "max_trials=100000000000000000000000",
     "parameter max_trials must be in [1, 1000000], got 100000000000000000000000"),
    ("pole-full", "max_trials=2.5", "parameter max_trials must be a whole number in [1, 1000000], got 2.5"),
    ("pole-full", "hidden=1e8", "parameter hidden must be in [0, 1024], got 100000000"),
    ("pole-full", "test_steps=1e7", "parameter test_steps must be in [1, 1000000], got 10000000"),
    ("recharge-flat", "hidden=1e8", "parameter hidden must be in [1, 1024], got 100000000"),
    ("recharge-behaviours", "capacity=1e6", "parameter capacity must be in [1, 100000], got 1000000"),
    ("recharge-together", "pretrain_steps=1e9", "parameter pretrain_steps must be in [0, 10000000], got 1000000000"),
    ("integration", "context=2000", "parameter context must be in [0, 1024], got 2000"),
    ("robot-teaching-dp", "hidden_fraction=1e8", "parameter hidden_fraction must be in [0, 10.0], got 100000000.0"),
    ("robot-teaching-dp", "stuck_window=1000", "parameter stuck_window must be in [1, 100], got 1000"),
    ("robot-teaching-dp", "trials=1e7", "parameter trials must be in [1, 1000000], got 10000000"),
    ("robot-dp-copy", "copy_epochs=1e7", "parameter copy_epochs must be in [0, 1000000], got 10000000"),
    ("survival-eval", "eval_envs=1e9", "parameter eval_envs must be in [0, 100000], got 1000000000"),
    ("cup-task1", "lessons_per_trial=1e6", "parameter lessons_per_trial must be in [0, 100000], got 1000000"),
    ("cup-task1", 'table={"hq": 100000000}', "parameter table entry 'hq' must be in [0, 1024], got 100000000"),
    ("cup-task1", 'table={"window": 1000}', "parameter table entry 'window' must be in [1, 100], got 1000"),
    ("cup-task1", 'table={"hidden": 5}', "parameter table: unknown entry 'hidden'; allowed: window, hq"),
    ("cup-task1", "probe_steps=[1, 100000000]", "parameter probe_steps must hold whole numbers in [0, 1000]"),
    ("cup-task2-frozen", "freeze_at=1e9", "parameter freeze_at must be in [0, 1000000], got 1000000000"),
    ("cup-task1", "window_q_inv_t=[5]", "parameter window_q_inv_t must be two numbers > 0"),
    ("td-depth", "steps=1e9", "parameter steps must be in [1, 1000000], got 1000000000"),
    ("complexity", "j_max=13", "parameters j_min..j_max must satisfy j_min <= j_max <= 12"),
    ("complexity", "max_states=1e12", "parameter max_states must be in [1, 10000000], got 1000000000000"),
])
def test_a_size_beyond_its_cap_is_refused_before_any_run(name, setting, message, tmp_path, monkeypatch):
    assert message in _refused(name, setting, tmp_path, monkeypatch)


def test_a_whole_number_float_is_taken_as_the_int_it_spells():
    spec = SPECS["pole-full"]
    a, b = sweep_spec(spec, ["max_trials=1e3"]), sweep_spec(spec, ["max_trials=1000"])
    assert a.params.max_trials == 1000 and type(a.params.max_trials) is int
    assert a.name == b.name  # the same setting, however spelt, is the same run folder
    assert override(spec.params, {"hidden": 12.0}).hidden == 12
    with pytest.raises(ValueError, match=r"parameter hidden must be a whole number in \[0, 1024\], got True"):
        override(spec.params, {"hidden": True})


def test_other_parameter_sets_refuse_sizes_beyond_their_caps():
    with pytest.raises(ValueError, match=r"parameter trials must be in \[1, 1000000\], got 10000000"):
        TrainingPlan("DP", trials=10**7)
    with pytest.raises(ValueError, match="parameter task must be one of"):
        TrainingPlan("XX")
    with pytest.raises(ValueError, match="parameter lams must have at most 1000 entries, got 1001"):
        DepthParams(lams=(0.5,) * 1001)


def _sizes(params):
    """(name, value, cap) of every capped number in a parameter set (``table``'s sizes included)."""
    from connrl.experiments.hidden_state import TABLE_SIZES

    for f in dataclasses.fields(params):
        v, top = getattr(params, f.name), cap(f.name, field_kinds(f))
        if top is not None and isinstance(v, (int, float)) and not isinstance(v, bool):
            yield f.name, v, top
    for key, v in (getattr(params, "table", None) or {}).items():
        if key in TABLE_SIZES:
            yield f"table[{key!r}]", v, TABLE_SIZES[key][1]


def test_every_profile_and_variant_stays_within_a_tenth_of_its_caps():
    assert len(SPECS) >= 40
    seen = set()
    for name, spec in SPECS.items():
        for profile in spec.profiles:
            base, _ = spec.resolve(profile)
            for variant in spec.variants:
                for key, v, top in _sizes(spec.variant_params(base, variant)):
                    seen.add(key)
                    assert 10 * v <= top, f"{name}, {profile}, {variant.label}: {key} = {v} is near its cap {top}"
    assert set(CAPS) <= seen  # every named cap bounds some experiment's parameter
