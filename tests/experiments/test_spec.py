"""Experiment specs: parameter dataclasses, profiles and variants as checked overrides, for the toy spec and for
every registered experiment."""

import dataclasses
import re

import pytest

from connrl.experiments.registry import all_experiments
from connrl.experiments.spec import PROFILES, ExperimentSpec, Variant, as_dict
from tests.experiments.toy import ToyParams, spec

SPECS = all_experiments()
NAMES = sorted(SPECS)


def test_runs_override_and_unknown_profile():
    assert spec().resolve("full") == (ToyParams(n=7), 4)
    assert spec().resolve("tiny") == (ToyParams(), 2)
    assert spec().resolve("quick", runs=9)[1] == 9
    with pytest.raises(ValueError, match="unknown profile 'huge'; allowed: tiny, quick, full"):
        spec().resolve("huge")
    with pytest.raises(ValueError, match=">= 1"):
        spec().resolve("quick", runs=0)


def test_spec_requires_every_profile():
    with pytest.raises(ValueError, match="missing"):
        ExperimentSpec(name="x", title="x", section="-", run="m:f", params=ToyParams(), profiles={"tiny": {"runs": 1}},
                       variants=(), quantities=())


def test_spec_requires_runs_in_every_profile_and_a_dataclass_instance():
    profiles = {"tiny": {"runs": 1}, "quick": {"n": 3}, "full": {"runs": 2}}
    with pytest.raises(ValueError, match="profile 'quick' must set 'runs'"):
        ExperimentSpec(name="x", title="x", section="-", run="m:f", params=ToyParams(), profiles=profiles,
                       variants=(), quantities=())
    for params in ({"n": 5}, ToyParams):  # a plain dict, or the class instead of an instance
        with pytest.raises(TypeError, match="parameter dataclass instance"):
            ExperimentSpec(name="x", title="x", section="-", run="m:f", params=params,
                           profiles={p: {"runs": 1} for p in PROFILES}, variants=(), quantities=())


def test_variant_params_apply_on_top_of_the_profile():
    s = spec()
    base, _ = s.resolve("full")
    assert [s.variant_params(base, v) for v in s.variants] == [ToyParams(n=7), ToyParams(n=6)]
    assert as_dict(ToyParams(n=3)) == {"n": 3, "explode_at": None}


def _misspelt(key: str, allowed) -> str:
    """A plausible typo of ``key`` that is not a parameter name."""
    for typo in (key[:-1], key + key[-1], key.replace("_", ""), key + "_"):
        if typo and typo not in allowed:
            return typo
    raise AssertionError(key)


def _assert_names_key_and_allowed(err: pytest.ExceptionInfo, bad: str, allowed) -> None:
    msg = str(err.value)
    assert repr(bad) in msg and "allowed:" in msg, msg
    listed = msg.split("allowed:", 1)[1]
    assert all(name in listed for name in allowed), msg


@pytest.mark.parametrize("name", NAMES)
def test_a_misspelt_variant_key_is_refused_with_the_allowed_keys(name):
    s = SPECS[name]
    allowed = [f.name for f in dataclasses.fields(s.params)]
    assert s.variants, name
    for i in (0, len(s.variants) - 1):
        v = s.variants[i]
        key = next(iter(v.params), allowed[0])  # a key the variant sets, else any parameter
        bad = _misspelt(key, allowed)
        params = {bad if k == key else k: x for k, x in v.params.items()} if key in v.params else {bad: 1}
        variants = list(s.variants)
        variants[i] = Variant(v.label, params, v.thesis)
        with pytest.raises(ValueError, match=re.escape(f"experiment {name}, variant {v.label!r}")) as err:
            dataclasses.replace(s, variants=tuple(variants))
        _assert_names_key_and_allowed(err, bad, allowed)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("profile", PROFILES)
def test_a_misspelt_profile_key_is_refused_with_the_allowed_keys(name, profile):
    s = SPECS[name]
    allowed = [f.name for f in dataclasses.fields(s.params)]
    over = dict(s.profiles[profile])
    key = next((k for k in over if k != "runs"), allowed[-1])  # a key the profile sets, else any parameter
    bad = _misspelt(key, allowed)
    value = over.pop(key, 1)
    profiles = {**s.profiles, profile: {**over, bad: value}}
    with pytest.raises(ValueError, match=re.escape(f"experiment {name}, profile {profile!r}")) as err:
        dataclasses.replace(s, profiles=profiles)
    _assert_names_key_and_allowed(err, bad, allowed)


@pytest.mark.parametrize("name", NAMES)
def test_every_profile_and_variant_resolves_to_the_parameter_class(name):
    s = SPECS[name]
    cls = type(s.params)
    assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen
    for profile in PROFILES:
        base, runs = s.resolve(profile)
        assert type(base) is cls and isinstance(runs, int) and runs >= 1
        for v in s.variants:
            params = s.variant_params(base, v)
            assert type(params) is cls
            assert cls(**as_dict(params)) == params  # what a worker process rebuilds from a job
    assert s.run_function() is not None
