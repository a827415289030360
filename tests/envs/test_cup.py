"""CupCollectionEnv (thesis 7.5.1-7.5.3): dynamics, sensation, optimal steps by search, determinism."""

from collections import deque

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401  (registers connrl/ ids)
from connrl.envs.cup import (
    CUP_CELLS,
    INSTANCES,
    LEFT,
    OPTIMAL_STEPS,
    PICK_UP,
    RIGHT,
    START_CELLS,
    CupCollectionEnv,
    transition,
)

ON, OFF = 0.5, -0.5


def test_check_env_and_registration():
    for kwargs in ({}, {"random_bits": 2, "control_error": 0.15}):
        env = gym.make("connrl/CupCollection-v0", **kwargs)
        assert isinstance(env.unwrapped, CupCollectionEnv)
        check_env(env.unwrapped)


def _bfs_steps(instance: str) -> tuple[int, list[int]]:
    """Shortest action sequence collecting both cups, by BFS over the true state (position, cups)."""
    start = (START_CELLS[instance], frozenset(CUP_CELLS))
    parent = {start: None}
    queue = deque([start])
    while queue:
        state = queue.popleft()
        if not state[1]:
            path = []
            while parent[state] is not None:
                state, a = parent[state]
                path.append(a)
            return len(path), path[::-1]
        for a in (LEFT, RIGHT, PICK_UP):
            pos, cups, _, _ = transition(*state, a)
            nxt = (pos, cups)
            if nxt not in parent:
                parent[nxt] = (state, a)
                queue.append(nxt)
    raise AssertionError("goal unreachable")


def test_optimal_policy_takes_7_steps_per_instance_14_for_both():
    n_a, path_a = _bfs_steps("A")
    n_b, path_b = _bfs_steps("B")
    assert (n_a, n_b) == (7, 7) and n_a + n_b == 14 == len(INSTANCES) * OPTIMAL_STEPS
    assert path_a == [RIGHT, PICK_UP, RIGHT, RIGHT, RIGHT, RIGHT, PICK_UP]  # docs/RECONSTRUCTION.md, "Cup collection"
    assert path_b == [LEFT, PICK_UP, LEFT, LEFT, LEFT, LEFT, PICK_UP]
    # the env executes the plans: reward 1 only on the last pick-up, terminated (not truncated)
    env = CupCollectionEnv()
    for inst, path in (("A", path_a), ("B", path_b)):
        env.reset(seed=0, options={"instance": inst})
        rewards = []
        for i, a in enumerate(path):
            _, r, term, trunc, _ = env.step(a)
            rewards.append(r)
            assert term == (i == len(path) - 1) and not trunc
        assert rewards == [0.0] * 6 + [1.0]


def test_sensation_bits_along_instance_a():
    env = CupCollectionEnv()
    obs, info = env.reset(seed=0, options={"instance": "A"})
    assert info == {"instance": "A", "position": 2, "cups": (3, 7)}
    np.testing.assert_array_equal(obs, [OFF, ON, OFF, OFF])  # cup right
    obs, *_ = env.step(RIGHT)  # at the cup's cell: cannot sense it
    np.testing.assert_array_equal(obs, [OFF, OFF, OFF, OFF])
    obs, _, _, _, info = env.step(PICK_UP)
    assert info["cups"] == (7,)
    for _ in range(3):
        obs, *_ = env.step(RIGHT)
    np.testing.assert_array_equal(obs, [OFF, ON, OFF, OFF])  # at 6, cup at 7
    obs, *_ = env.step(RIGHT)
    obs, *_ = env.step(RIGHT)  # at 8: cup left
    np.testing.assert_array_equal(obs, [ON, OFF, OFF, OFF])
    obs, info = env.reset(options={"instance": "B"})
    np.testing.assert_array_equal(obs, [ON, OFF, OFF, OFF])  # cup left at the start of B


def test_walls_and_collision_bits():
    env = CupCollectionEnv()
    env.reset(seed=0, options={"instance": "A"})
    env.step(LEFT)
    obs, _, _, _, info = env.step(LEFT)  # at 0
    assert info["position"] == 0 and obs[2] == OFF
    obs, _, _, _, info = env.step(LEFT)  # into the left wall
    assert info["position"] == 0
    np.testing.assert_array_equal(obs, [OFF, OFF, ON, OFF])
    obs, *_ = env.step(PICK_UP)  # collision bit refers to the previous action only
    np.testing.assert_array_equal(obs, [OFF, OFF, OFF, OFF])
    env.reset(options={"instance": "B"})
    env.step(RIGHT)
    env.step(RIGHT)  # at 10
    obs, _, _, _, info = env.step(RIGHT)
    assert info["position"] == 10
    np.testing.assert_array_equal(obs, [OFF, OFF, OFF, ON])


def test_pick_up_on_empty_cell_does_nothing_and_timeout_truncates():
    env = CupCollectionEnv()
    env.reset(seed=0, options={"instance": "A"})
    for t in range(30):
        _, r, term, trunc, info = env.step(PICK_UP)
        assert r == 0.0 and not term and info["cups"] == (3, 7)
        assert trunc == (t == 29)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(PICK_UP)


def test_reset_draws_both_instances_and_is_seeded():
    env = CupCollectionEnv()
    draws = [env.reset(seed=s)[1]["instance"] for s in range(40)]
    assert set(draws) == {"A", "B"}
    assert draws == [env.reset(seed=s)[1]["instance"] for s in range(40)]


def test_control_error_on_and_off():
    env = CupCollectionEnv(control_error=0.15)
    env.reset(seed=1, options={"instance": "A"})
    failures = 0
    n = 0
    for _ in range(200):
        env.reset(options={"instance": "A"})
        for _ in range(8):  # 2 -> 10 at most: no wall collision
            pos = env.unwrapped.position
            _, _, _, _, info = env.step(RIGHT)
            n += 1
            if info["control_error_occurred"]:
                failures += 1
                assert info["position"] == pos  # no effect at all
            else:
                assert info["position"] == pos + 1
    assert 0.12 < failures / n < 0.18  # 1600 Bernoulli(0.15) draws: sd 0.009
    env = CupCollectionEnv(control_error=0.0)
    env.reset(seed=1, options={"instance": "A"})
    assert not any(env.step(RIGHT)[4]["control_error_occurred"] for _ in range(8))


def test_random_bits_are_appended_fair_and_seeded():
    env = CupCollectionEnv(random_bits=2)
    obs, _ = env.reset(seed=3, options={"instance": "A"})
    assert obs.shape == (6,) and env.observation_space.contains(obs)
    np.testing.assert_array_equal(obs[:4], [OFF, ON, OFF, OFF])
    bits = [obs[4:]]
    for _ in range(29):
        obs, *_ = env.step(PICK_UP)
        bits.append(obs[4:])
    bits = np.array(bits)
    assert set(np.unique(bits)) == {OFF, ON}
    assert 0.3 < (bits == ON).mean() < 0.7


def _rollout(env, seed, n_episodes=5):
    out = []
    env.reset(seed=seed)
    for _ in range(n_episodes):
        obs, info = env.reset()
        out.append((info["instance"], obs.tolist()))
        done = False
        k = 0
        while not done:
            obs, r, term, trunc, info = env.step(k % 3)
            k += 1
            out.append((obs.tolist(), r, term, trunc, info["control_error_occurred"]))
            done = term or trunc
    return out


def test_determinism_same_seed_same_trajectory():
    a = _rollout(CupCollectionEnv(random_bits=2, control_error=0.15), seed=7)
    b = _rollout(CupCollectionEnv(random_bits=2, control_error=0.15), seed=7)
    c = _rollout(CupCollectionEnv(random_bits=2, control_error=0.15), seed=8)
    assert a == b and a != c


def test_bad_arguments_are_rejected():
    with pytest.raises(ValueError, match="random_bits"):
        CupCollectionEnv(random_bits=-1)
    with pytest.raises(ValueError, match="control_error"):
        CupCollectionEnv(control_error=1.5)
    with pytest.raises(ValueError, match="max_steps"):
        CupCollectionEnv(max_steps=0)
    env = CupCollectionEnv()
    with pytest.raises(ValueError, match="instance"):
        env.reset(options={"instance": "C"})
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(3)


def test_render_ansi():
    env = CupCollectionEnv(render_mode="ansi")
    env.reset(seed=0, options={"instance": "A"})
    assert env.render() == "|. . I C . . . C . . .|"
