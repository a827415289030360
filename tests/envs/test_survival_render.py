"""Survival rendering: ANSI text and RGB frames."""

import numpy as np

from connrl.envs.survival import (
    SurvivalEnv,
)


def test_renders():
    env = SurvivalEnv(render_mode="ansi")
    env.reset(seed=0)
    text = env.render()
    lines = text.splitlines()
    assert lines[1 + 18][3 + 12] == "I" and lines[1 + 1][3 + 12] == "E" and text.count("$") == 15 + 1
    assert "energy  40" in text
    env = SurvivalEnv(render_mode="rgb_array", action_representation="local")
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    colours = {tuple(c) for c in frame.reshape(-1, 3)[::7]}
    obstacle, enemy, food, agent = (70, 74, 86), (200, 30, 40), (226, 160, 20), (30, 90, 220)
    assert {obstacle, enemy, food, agent} <= colours
