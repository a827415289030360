"""Robot task envs (DK, DP, WFL, WFR): API, observations, reinforcement in the env, goals, seeds, rendering."""


import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401
from connrl.envs.robot import (
    KEYMAP,
    MOVE_BACKWARD,
    MOVE_FORWARD,
    OBS_SIZE,
    TASKS,
    TURN_LEFT_60,
    Layout,
    RobotTaskEnv,
    encode_sonar,
    side_alignment,
    side_clearance,
    wall_following_reward,
)
from tests.envs.robot_scenes import BODY_CANCEL


def exact(task, **kw):
    """Noise-free, in the world the scenes' hand-drawn numbers are for (tests.envs.robot_scenes.BODY_CANCEL)."""
    return RobotTaskEnv(task, noise=False, **(BODY_CANCEL | kw))


@pytest.mark.parametrize("task", TASKS)
def test_check_env(task):
    check_env(gym.make(f"connrl/Robot-{task}-v0").unwrapped, skip_render_check=True)
    env = gym.make(f"connrl/Robot-{task}-v0")
    obs, info = env.reset(seed=0)
    assert obs.shape == (OBS_SIZE[task],) and env.observation_space.contains(obs)
    assert set(info) >= {"pose", "success", "collision", "room"}


def test_observation_layouts_and_binary_low():
    env = exact("DK")
    obs, _ = env.reset(seed=0, options={"start": (40, 40, 225)})  # facing the light
    assert obs[24] == 0.5 and set(obs[25:52].tolist()) == {-0.5}  # light on ray 0 only, no collision
    env = exact("DK", binary_low=0.0)
    obs, _ = env.reset(seed=0, options={"start": (40, 40, 225)})
    assert obs[24] == 1.0 and set(obs[25:52].tolist()) == {0.0}  # 0/1 binaries of 5.4.4
    assert env.observation_space.contains(obs)
    env = exact("WFL")
    obs, _ = env.reset(seed=0, options={"start": (32, 100, 90)})  # west wall 20 in off the left side
    assert obs.shape == (36,)
    assert obs[28] == pytest.approx(0.0, abs=1e-6)  # parallel to the left wall
    assert obs[30:33].tolist() == [-0.5, 0.5, -0.5]  # left clearance just right
    assert obs[33:36].tolist() == [-0.5, -0.5, 0.5]  # right: too far


def test_collision_bits_in_observation():
    env = exact("DP")
    env.reset(seed=0, options={"start": (114, 400, 90)})  # 8 in from the north wall, facing it
    obs, r, term, trunc, info = env.step(MOVE_FORWARD)
    assert r == -10 and info["collision"] and info["collision_side"] == "front"
    assert obs[48:52].tolist() == [0.5, -0.5, -0.5, -0.5]
    assert info["pose"] == (114, 400, 90)


# --- reinforcement, goals and collisions in the env --------------------------------------------
def test_env_wf_reward_matches_reference_function():
    for task, side in (("WFL", "left"), ("WFR", "right")):
        env = RobotTaskEnv(task)
        env.reset(seed=1)
        acts = np.random.default_rng(0).integers(0, 6, 300)
        for a in acts:
            _, r, term, trunc, info = env.step(int(a))
            assert r == wall_following_reward(int(a), info["collision"], env.sim.sense().ranges, side) or (
                info["collision"] and r == -10)
            if trunc:
                env.reset()


def test_wf_following_west_wall_earns_ten():
    env = exact("WFL")
    env.reset(seed=0, options={"start": (32, 150, 90)})
    rewards = [env.step(MOVE_FORWARD)[1] for _ in range(5)]
    assert rewards == [10.0] * 5
    env = exact("WFR")
    env.reset(seed=0, options={"start": (32, 150, 270)})  # heading south: west wall on the right
    assert env.step(MOVE_FORWARD)[1] == 10.0
    assert env.step(MOVE_BACKWARD)[1] == -3.0


def test_dk_docking_head_on_succeeds():
    env = exact("DK")
    env.reset(seed=0, options={"start": (30, 30, 225)})
    obs, r, term, trunc, info = env.step(MOVE_FORWARD)
    assert (r, term, trunc, info["success"]) == (100.0, True, False, True)


def test_dk_other_contacts_are_collisions():
    env = exact("DK")
    env.reset(seed=0, options={"start": (30, 30, 45)})
    _, r, term, _, info = env.step(MOVE_BACKWARD)  # backs into the charger
    assert (r, term, info["success"], info["collision_side"]) == (-10.0, False, False, "back")
    # Driving south at x=27 the charger corner (18, 18) touches the body 48.7 deg right of the heading:
    # a forward bump into the charger, but not head-on (> 30 deg), so a collision.
    env.reset(seed=0, options={"start": (27, 35, 270)})
    _, r, term, _, info = env.step(MOVE_FORWARD)
    assert (r, term, info["success"], info["collision_side"]) == (-10.0, False, False, "right")


def test_dp_success_when_the_centre_gets_into_another_room():
    env = exact("DP")
    env.reset(seed=0, options={"start": (114, 330, 270)})  # above door A, facing it
    out = [env.step(MOVE_FORWARD) for _ in range(3)]  # y: 318, 306 (still in C), 294 (in A)
    assert [o[1] for o in out] == [0, 0, 100]
    assert [o[2] for o in out] == [False, False, True]
    assert out[-1][4]["room"] == "A" and out[-1][4]["pose"][1] == pytest.approx(294)
    assert out[1][4]["room"] == "C" and not out[1][4]["success"]  # body in the doorway, centre not through
    # Backing through counts too: it is the room that matters (6.5), not the heading.
    env.reset(seed=0, options={"start": (246, 306, 90)})  # in C just above door B, facing away
    _, r, term, _, info = env.step(MOVE_BACKWARD)
    assert (r, term, info["room"]) == (100.0, True, "B")
    # The stricter variant asks for the centre pass_depth in from every doorway segment.
    env = exact("DP", pass_depth=24.0)
    env.reset(seed=0, options={"start": (114, 330, 270)})
    out = [env.step(MOVE_FORWARD) for _ in range(5)]
    assert [o[1] for o in out] == [0, 0, 0, 0, 100]


def test_dp_jamb_collision():
    env = exact("DP", layout=Layout.load("default").with_door_width(36.0))  # the SPEC reconstruction's doors
    # 8 in off door A's axis (6 in of slack per side): the body touches the west jamb (96, 300) when the
    # centre is at y = 300 + sqrt(12^2 - 10^2) = 306.6, so the second move south (318 -> 306) is cancelled,
    # the contact 56.4 deg right of the heading.
    env.reset(seed=0, options={"start": (106, 330, 270)})
    assert env.step(MOVE_FORWARD)[1] == 0
    _, r, term, _, info = env.step(MOVE_FORWARD)
    assert (r, term, info["collision_side"], info["room"]) == (-10.0, False, "right", "C")
    assert info["pose"][1] == pytest.approx(318)
    # 5 in off the axis the body clears the jamb by 1 in and the robot gets through.
    env.reset(seed=0, options={"start": (109, 330, 270)})
    assert [env.step(MOVE_FORWARD)[1] for _ in range(3)] == [0, 0, 100]
    # a 48-in door (12 in of slack per side): 8 in off the axis passes, 14 in off hits the jamb at x = 90
    env = exact("DP", layout=Layout.load("default").with_door_width(48.0))
    env.reset(seed=0, options={"start": (106, 330, 270)})
    assert [env.step(MOVE_FORWARD)[1] for _ in range(3)] == [0, 0, 100]
    env.reset(seed=0, options={"start": (100, 330, 270)})  # 10 in from the jamb (90, 300), as above
    assert env.step(MOVE_FORWARD)[1] == 0
    _, r, _, _, info = env.step(MOVE_FORWARD)
    assert (r, info["collision_side"]) == (-10.0, "right")


def test_truncation_after_max_steps():
    for task in TASKS:
        env = exact(task, max_steps=30)
        env.reset(seed=0, options={"start": (300, 60, 0)} if task != "DK" else None)
        for t in range(30):
            _, _, term, trunc, _ = env.step(TURN_LEFT_60)
            assert not term and trunc == (t == 29)


def test_fixed_test_tasks_and_seed_reproducibility():
    env = RobotTaskEnv("DP")
    tasks = [env.sample_task(np.random.default_rng(7)) for _ in range(3)]
    assert tasks[0] == tasks[1] == tasks[2]

    def run(seed):
        out = []
        env.reset(seed=seed, options={"start": tasks[0]})
        for a in np.random.default_rng(1).integers(0, 6, 30):
            obs, r, term, trunc, info = env.step(int(a))
            out.append(np.concatenate([obs, [r], info["pose"]]))
            if term or trunc:
                break
        return np.array(out)

    assert np.array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))
    o1, _ = RobotTaskEnv("WFL").reset(seed=3)
    o2, _ = RobotTaskEnv("WFL").reset(seed=3)
    assert np.array_equal(o1, o2)


def test_bad_arguments_are_rejected():
    with pytest.raises(ValueError, match="task must be one of"):
        RobotTaskEnv("XX")
    with pytest.raises(ValueError, match="render_mode"):
        RobotTaskEnv("DK", render_mode="window")
    env = RobotTaskEnv("DK")
    with pytest.raises(ValueError, match="overlaps"):
        env.reset(options={"start": (5, 100, 0)})
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"begin": (50, 50, 0)})
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be in 0..5"):
        env.step(7)


def test_changed_layout_runs():
    env = RobotTaskEnv("DK", layout="changed")
    obs, info = env.reset(seed=0)
    assert env.layout.name == "changed" and obs.shape == (52,)


def test_keymap_covers_six_actions():
    assert sorted(KEYMAP.values()) == list(range(6))


def test_render_modes():
    env = RobotTaskEnv("DP", render_mode="rgb_array", render_rays=True)
    env.reset(seed=0)
    env.step(MOVE_FORWARD)
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and len(env.trace) == 2
    with pytest.warns(UserWarning, match="headless"):
        human = RobotTaskEnv("DP", render_mode="human")
        human.reset(seed=0)
    human.close()


def test_compiled_observation_matches_reference_encoding():
    for task in TASKS:
        env = RobotTaskEnv(task)
        env.reset(seed=4)
        for a in np.random.default_rng(2).integers(0, 6, 40):
            obs, *_ = env.step(int(a))
            rd = env._reading
            assert np.allclose(obs[:24], encode_sonar(rd.sonar), atol=1e-6)
            if task in ("WFL", "WFR"):
                for j, side in enumerate(("left", "right")):
                    body = rd.sonar - 12.0  # the default sonar reads from the centre; 5.3.1 wants body distances
                    par = 0.5 * np.clip(side_alignment(body, side) / 45, -1, 1)
                    assert obs[28 + j] == pytest.approx(par, abs=1e-6)
                    c = side_clearance(body, side)
                    assert obs[30 + 3 * j: 33 + 3 * j].tolist() == [0.5 if b else -0.5 for b in
                                                                     (c < 14, 14 <= c <= 32, c > 32)]
            else:
                bits = rd.light if task == "DK" else rd.door_edge
                assert np.array_equal(obs[24:48] > 0, bits.astype(bool))
            if env._steps >= 30:
                env.reset()
