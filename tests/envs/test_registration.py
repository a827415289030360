"""``import connrl`` registers every world with Gymnasium: ``gymnasium.make("connrl/...")`` needs nothing else."""

import subprocess
import sys

from connrl.envs import _ENVS


def test_import_connrl_alone_makes_every_world():
    code = ("import gymnasium, connrl\n"
            f"for env_id in {sorted(_ENVS)!r}:\n"
            "    env = gymnasium.make(env_id)\n"
            "    env.reset(seed=0)\n"
            "    env.step(env.action_space.sample())\n"
            "print('ok')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
