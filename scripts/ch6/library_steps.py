"""How many primitive steps did the shipped behaviour library's training take? (6.7's equal-cost count)

The library's index (connrl/data/behaviours/library.json) was written before the trainer recorded steps. This re-runs
``connrl.experiments.behaviours.train_behaviour``'s loop with each behaviour's plan and seed (0-3, as
``train_library`` gave them), counts the primitive steps of its 1,500 training trials, and checks that the re-trained
Q-nets equal the shipped ones (largest |Q difference| over 41 observations of a test world), so the count is the
shipped library's own. With --write it stores each count as "steps" in library.json (not part of the library's
digest, so no run changes). About 15-20 s a behaviour.

    python scripts/ch6/library_steps.py [--write]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace

import numpy as np

from connrl.envs.robot.tasks import sample_anywhere
from connrl.experiments.behaviours import PLANS
from connrl.experiments.robot import RobotParams, RobotRun
from connrl.storage import atomic_write_text
from connrl.tasks.behaviours import LIBRARY_DIR, load_library


def count(plan, seed: int, shipped) -> tuple[int, float]:
    p = replace(RobotParams(), task=plan.task, lessons=plan.lessons, trials=plan.trials)
    rng = np.random.default_rng(seed)
    run = RobotRun(p, rng)
    layout = run.env.unwrapped.layout
    steps = 0
    for k in range(p.trials):  # train_behaviour's loop, step for step
        far = plan.far_share > 0 and rng.random() < plan.far_share
        steps += run.train(k, options={"start": sample_anywhere(rng, layout)} if far else None).steps
    env, obs_rng = run.test_env, np.random.default_rng(1)
    o, _ = env.reset(seed=1)
    observations = [o]
    for _ in range(40):
        o, *_ = env.step(int(obs_rng.integers(env.action_space.n)))
        observations.append(o)
    diff = max(float(np.max(np.abs(run.agent.q.values(np.asarray(x, float)) - shipped.q_values(x))))
               for x in observations)
    return steps, diff


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="store the counts in library.json")
    args = ap.parse_args()
    index_file = LIBRARY_DIR / "library.json"
    doc, lib = json.loads(index_file.read_text()), load_library()
    for plan in PLANS:
        meta = doc["behaviours"][plan.task]
        steps, diff = count(replace(plan, trials=meta["trials"]), meta["seed"], lib[plan.task])
        print(f"{plan.task}: {meta['trials']} trials, {steps} primitive steps; re-trained nets differ from the shipped "
              f"by at most {diff:.1e}")
        if diff > 1e-6:
            raise SystemExit(f"{plan.task}: the re-trained nets are not the shipped ones; the count is not theirs")
        meta["steps"] = steps
    if args.write:
        atomic_write_text(index_file, json.dumps(doc, indent=1) + "\n")
        print(f"written: {index_file}")


if __name__ == "__main__":
    main()
