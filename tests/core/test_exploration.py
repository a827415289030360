"""Boltzmann selection (Eq. 3.4/3.6), temperature schedules, stuck detection."""

import numpy as np
import pytest

from connrl.core.exploration import (
    StuckConfig,
    StuckDetector,
    TemperatureSchedule,
    boltzmann_probabilities,
    boltzmann_select,
)


def test_boltzmann_by_hand():
    p = boltzmann_probabilities(np.array([0.0, np.log(3.0)]), 1.0)
    np.testing.assert_allclose(p, [0.25, 0.75])
    p = boltzmann_probabilities(np.array([1.0, 2.0, 3.0]), 0.5)
    e = np.exp(np.array([2.0, 4.0, 6.0]))
    np.testing.assert_allclose(p, e / e.sum())


def test_zero_temperature_is_greedy():
    a, p = boltzmann_select(np.array([0.1, 0.7, 0.3]), 0.0, np.random.default_rng(0))
    assert a == 1 and p[1] == 1.0


def test_large_merits_do_not_overflow():
    p = boltzmann_probabilities(np.array([1000.0, 999.0]), 0.01)
    assert np.isfinite(p).all() and p[0] > 0.99


def test_sampling_frequencies():
    rng = np.random.default_rng(0)
    m = np.array([0.0, np.log(3.0)])
    picks = [boltzmann_select(m, 1.0, rng)[0] for _ in range(20000)]
    assert np.mean(picks) == pytest.approx(0.75, abs=0.01)


def test_schedules_both_ways():
    inv = TemperatureSchedule.inverse(10, 30, 3)  # 1/T: 10 -> 30 over 3 trials
    assert [inv(t) for t in (0, 1, 2, 9)] == pytest.approx([0.1, 0.05, 1 / 30, 1 / 30])
    direct = TemperatureSchedule.direct(0.05, 0.02, 4)  # T: 0.05 -> 0.02
    assert [direct(t) for t in (0, 3, 100)] == pytest.approx([0.05, 0.02, 0.02])
    with pytest.raises(ValueError, match="kind"):
        TemperatureSchedule(1, 2, 3, "log")
    with pytest.raises(ValueError, match="> 0"):
        TemperatureSchedule.inverse(0, 2, 3)
    with pytest.raises(ValueError, match="temperature"):
        boltzmann_probabilities(np.zeros(2), -1.0)


def test_stuck_detection_raises_temperature_only_when_stuck():
    d = StuckDetector(StuckConfig(window=4, radius=1.0, boost=3.0))
    assert [d.factor((0, 0)) for _ in range(4)] == [1, 1, 1, 3.0]  # staying put
    d.reset()
    assert [d.factor((i * 2, 0)) for i in range(6)][-1] == 1.0  # moving on


# --- Eq. 6.6 and the persistence rule (Ch. 6) ------------------------------------------------------
def test_weighted_boltzmann_by_hand():
    from connrl.core.exploration import weighted_boltzmann_probabilities as wb

    q, t = np.array([0.0, 0.1, 0.2, 0.0]), 0.1
    w = np.array([1.0, 0.0, 1.0, 100.0])
    e = np.array([1.0, 0.0, np.e ** 2, 100.0])  # W(b) exp(Q/T): 1, 0, e^2, 100
    np.testing.assert_allclose(wb(q, w, t), e / e.sum(), rtol=1e-12)
    np.testing.assert_allclose(wb(q, np.ones(4), t), boltzmann_probabilities(q, t), rtol=1e-12)  # W = 1: Eq. 3.4
    assert wb(q, w, 0.0).tolist() == [0.0, 0.0, 1.0, 0.0]  # greedy among the applicable (b = 1 is ruled out)
    assert wb(np.array([1e4, -1e4]), np.array([1.0, 1.0]), 0.01).tolist() == [1.0, 0.0]  # no overflow
    for bad in ([0.0, 0.0, 0.0, 0.0], [1.0, -1.0, 1.0, 1.0], [1.0, 1.0]):
        with pytest.raises(ValueError, match="weights"):
            wb(q, np.array(bad), t)


def test_persistence_weights_follow_experiment_3():
    from connrl.core.exploration import persistence_weights as pw

    app = np.array([False, True, True, True])  # DK inapplicable; DP, WFL, WFR applicable
    assert pw(app, None, None, False).tolist() == [0, 1, 1, 1]  # the first step: Exp. 2's 0/1
    assert pw(app, app, 2, False).tolist() == [0, 1, 100, 1]  # keep following WFL
    assert pw(app, app, 1, True).tolist() == [0, 1, 1, 1]  # DP just passed its door: no persistence
    before = np.array([False, False, True, True])
    assert pw(app, before, 2, False).tolist() == [0, 1, 1, 1]  # DP became applicable: a significant change
    assert pw(np.array([False, False, True, True]), app, 1, False).tolist() == [0, 0, 1, 1]  # active DP inapplicable


def test_boltzmann_select_draws_by_the_inverse_distribution_of_boltzmann_probabilities():
    """Its lean path (it runs at every training step) gives exactly Eq. 3.4's distribution and the inverse-CDF draw
    from it, with one uniform from the generator."""
    rng = np.random.default_rng(4)
    for _ in range(3000):
        merits = rng.normal(size=int(rng.integers(2, 7))) * rng.choice([0.01, 1.0, 100.0])
        t = float(rng.choice([0.02, 0.5, 3.0]))
        seed = int(rng.integers(1 << 30))
        a, p = boltzmann_select(merits, t, np.random.default_rng(seed))
        ref_p = boltzmann_probabilities(merits, t)
        u = np.random.default_rng(seed).random()
        np.testing.assert_array_equal(p, ref_p)
        assert a == min(int(np.searchsorted(np.cumsum(ref_p), u, side="right")), len(merits) - 1)
        assert boltzmann_select(list(merits), t, np.random.default_rng(seed))[0] == a  # any sequence of numbers
