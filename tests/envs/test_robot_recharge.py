"""The recharging task CHG (Ch. 6): Gymnasium API, the 16 high-level inputs by hand, the flat input, docking,
time limit and per-room starts."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import connrl.envs  # noqa: F401
from connrl.envs.robot import MOVE_FORWARD, TURN_LEFT_15, Layout, RobotTaskEnv, encode_sonar
from connrl.envs.robot.recharge import FLAT_SIZE, ROOMS, RechargeEnv, global_sonar, high_level_inputs
from connrl.envs.robot.sim import Reading


@pytest.mark.parametrize("env_id", ["connrl/Robot-CHG-v0", "connrl/Robot-CHG-Flat-v0", "connrl/Robot-CHG-NoXY-v0"])
def test_check_env(env_id):
    check_env(gym.make(env_id).unwrapped, skip_render_check=True)


def test_global_sonar_sectors_by_hand():
    # facing east (heading 0) ray k points at 15k deg: north (sector 0) is rays 5, 6, 7; west (2) rays 11, 12, 13;
    # east (6) rays 23, 0, 1. Facing north the same readings turn by 90 deg: north is rays 23, 0, 1.
    s = np.arange(24.0)
    assert global_sonar(s, 0.0).tolist() == [6, 9, 12, 15, 18, 21, 8, 3]
    assert global_sonar(s, 90.0).tolist() == [8, 3, 6, 9, 12, 15, 18, 21]
    assert global_sonar(s, 7.0).tolist() == global_sonar(s, 0.0).tolist()  # within a sector's half-width


def test_compiled_sonar_units_equal_the_numpy_definition():
    rng = np.random.default_rng(0)
    for _ in range(200):
        sonar, heading = rng.uniform(-5.0, 140.0, 24), float(rng.uniform(0.0, 360.0))
        x = high_level_inputs(Reading(sonar, sonar, *[np.zeros(24, np.uint8)] * 2, np.zeros(4, np.uint8), heading,
                                      "A"), 10.0, 10.0, Layout.load("default"))
        np.testing.assert_array_equal(x[:8], encode_sonar(global_sonar(sonar, heading)).astype(np.float32))


def test_high_level_inputs_by_hand():
    L = Layout.load("default")
    sonar = np.full(24, 32.0)
    sonar[[5, 6, 7]] = 0.0  # something touching the robot's north side (heading 0)
    bits = np.zeros(24, np.uint8)
    rd = Reading(sonar, sonar, bits, bits.copy(), np.array([0, 0, 1, 0], np.uint8), 0.0, "B")
    x = high_level_inputs(rd, 270.0, 105.0, L)
    assert x[:8].tolist() == [1.0] + [0.5] * 7  # encoded sonar: 0 in -> 1, 32 in -> 0.5
    assert x[8:11].tolist() == [0.5, -0.5, -0.5]  # collision on, no light, no door edge
    assert x[11:14].tolist() == [-0.5, 0.5, -0.5]  # room B
    assert x[14:16].tolist() == [0.25, -0.25]  # 270/360 - 0.5, 105/420 - 0.5


def test_flat_input_holds_each_elementary_input_and_the_high_level_ones():
    flat, high = RechargeEnv(obs="flat"), RechargeEnv(obs="high")
    f, info = flat.reset(seed=3)
    h, _ = high.reset(seed=3)
    assert f.shape == (FLAT_SIZE,) == (100,)
    np.testing.assert_array_equal(f[-16:], h)
    np.testing.assert_array_equal(f[:48], info["task_obs"]["DK"][:48])
    np.testing.assert_array_equal(f[48:72], info["task_obs"]["DP"][24:48])


def test_docking_ends_the_trial_with_100_and_collisions_cost_only_if_asked():
    env = RechargeEnv(noise=False)
    env.reset(seed=0, options={"start": (40.0, 40.0, 225.0)})  # on the charger's diagonal, facing it
    assert env.step(MOVE_FORWARD)[1:3] == (0.0, False)
    _, r, term, trunc, info = env.step(MOVE_FORWARD)  # the body meets the box's corner head-on
    assert (r, term, trunc, info["success"]) == (100.0, True, False, True)
    env = RechargeEnv(noise=False, collision_penalty=-5.0)
    env.reset(seed=0, options={"start": (100.0, 14.0, 270.0)})  # 2 in from the south wall, facing it
    assert env.step(MOVE_FORWARD)[1] == -5.0
    with pytest.raises(ValueError, match="collision_penalty"):
        RechargeEnv(collision_penalty=5.0)


def test_time_limit_truncates_after_max_steps():
    env = RechargeEnv(max_steps=3)
    env.reset(seed=1)
    out = [env.step(TURN_LEFT_15) for _ in range(3)]
    assert [o[3] for o in out] == [False, False, True] and not any(o[2] for o in out)


def test_starts_per_room_and_all_rooms():
    env = RechargeEnv()
    for room in ROOMS:
        for s in range(20):
            _, info = env.reset(seed=s, options={"room": room})
            assert info["room"] == info["start_room"] == room
    rooms = [env.reset(seed=s)[1]["start_room"] for s in range(300)]
    assert all(abs(rooms.count(r) / 300 - 1 / 3) < 0.08 for r in ROOMS)  # each room about a third
    with pytest.raises(ValueError, match="start_room"):
        RechargeEnv(start_room="D")
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"rooom": "A"})


def test_deterministic_given_the_seed():
    def run(seed):
        env = RechargeEnv(obs="flat")
        obs, _ = env.reset(seed=seed)
        out = [obs]
        for a in [4, 0, 4, 2, 4, 5]:
            out.append(env.step(a)[0])
        return np.array(out)

    np.testing.assert_array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))


@pytest.mark.parametrize("task", ["DK", "DP", "WFL", "WFR"])
def test_task_observations_equal_ch5_environments_on_the_same_scan(task):
    """Same pose and seed, so the same noisy scan: each behaviour sees exactly what it saw when it was learned."""
    start = (250.0, 120.0, 33.0)
    _, info = RechargeEnv().reset(seed=11, options={"start": start})
    ch5, _ = RobotTaskEnv(task).reset(seed=11, options={"start": start})
    np.testing.assert_array_equal(info["task_obs"][task], ch5)


def test_step_scale_shrinks_moves_and_turns_and_the_reward_is_settable():
    """Experiment 4 (6.6.4): a fifth of each primitive action, "2.4 inches at a time"; docking pays success_reward."""
    env = RechargeEnv(noise=False, step_scale=0.2, success_reward=500.0)
    env.reset(seed=0, options={"start": (40.0, 250.0, 0.0)})  # open floor of room A, facing east
    env.step(MOVE_FORWARD)
    assert env.sim.pose == pytest.approx((42.4, 250.0, 0.0))
    env.step(TURN_LEFT_15)
    assert env.sim.pose[2] == pytest.approx(3.0)
    env.reset(seed=0, options={"start": (40.0, 40.0, 225.0)})  # 19 in from the charger's corner, facing it
    steps = []
    while not steps or not steps[-1][2]:
        steps.append(env.step(MOVE_FORWARD))
    assert len(steps) == 8 and [s[1] for s in steps] == [0.0] * 7 + [500.0]  # 19.1 / 2.4 -> the 8th move docks
    for bad in ({"step_scale": 0.0}, {"step_scale": 1.5}, {"success_reward": 0.0}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            RechargeEnv(**bad)


def test_without_xy_the_inputs_are_the_first_14_and_the_two_doorways_look_nearly_alike():
    with_xy, no_xy = RechargeEnv(obs="high"), RechargeEnv(obs="high", xy=False)
    a, _ = with_xy.reset(seed=5)
    b, _ = no_xy.reset(seed=5)
    assert no_xy.observation_space.shape == (14,) and b.shape == (14,)
    np.testing.assert_array_equal(a[:14], b)
    # the Ch. 8 hidden state: facing north in front of each doorway (Fig. 5.3's L3 and L4, subgoals 4 and 5), the
    # noise-free 14 inputs differ only in the west/east sonar units, by less than the sonar noise makes them vary
    env = RechargeEnv(obs="high", xy=False, noise=False)
    views = [env.reset(seed=0, options={"start": tuple(env.layout.locations[k])})[0] for k in ("L3", "L4")]
    d = np.abs(views[0] - views[1])
    assert d[8:].max() == 0.0 and 0 < d.max() < 0.1
    assert RechargeEnv(obs="flat", xy=False).observation_space.shape == (FLAT_SIZE - 2,)
    with pytest.raises(ValueError, match="xy must be"):
        RechargeEnv(xy="no")


def test_xy_scale_stretches_the_xy_units_and_their_bounds():
    L = Layout.load("default")
    bits = np.zeros(24, np.uint8)
    rd = Reading(np.full(24, 32.0), np.full(24, 32.0), bits, bits.copy(), np.zeros(4, np.uint8), 0.0, "B")
    assert high_level_inputs(rd, 270.0, 105.0, L, xy_scale=8.0)[14:16].tolist() == [2.0, -2.0]  # 8 x (0.25, -0.25)
    for obs, n in (("high", 16), ("flat", FLAT_SIZE)):
        env = RechargeEnv(obs=obs, xy_scale=8.0)
        space = env.observation_space
        assert space.shape == (n,) and space.low[-2:].tolist() == [-4.0] * 2 and space.high[-2:].tolist() == [4.0] * 2
        assert space.low[:-2].min() == -0.5 and space.high[:-2].max() == 1.0  # the other units keep their range
        check_env(env, skip_render_check=True)
        x, _ = env.reset(seed=1)
        assert np.all(np.abs(x[-2:]) <= 4.0) and np.abs(x[-2:]).max() > 0.5  # stretched, inside the bounds
    no_xy = RechargeEnv(xy=False, xy_scale=8.0).observation_space
    assert no_xy.shape == (14,) and no_xy.high.max() == 1.0  # no X-Y, nothing stretched
    for bad in (0, -1.0, float("nan"), float("inf"), True, "8"):
        with pytest.raises(ValueError, match="xy_scale must be a finite number > 0"):
            RechargeEnv(xy_scale=bad)


def test_the_behaviour_level_learners_worlds_take_the_runs_xy_scale():
    from connrl.experiments.integration import IntegrationParams
    from connrl.experiments.recharge import RechargeParams
    from connrl.tasks.integration import make_integration_env
    from connrl.tasks.recharge import BehaviourEnv, make_recharge_env

    assert make_recharge_env(RechargeParams()).world.xy_scale == RechargeParams().xy_scale == 8.0
    assert make_integration_env(IntegrationParams(xy=True), "changed").world.xy_scale == 8.0
    check_env(BehaviourEnv(xy_scale=8.0), skip_render_check=True)
