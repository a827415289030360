"""How well the learned survival model (4.2.5) predicts, by learning rate, on fixed experiences (issue 31).

    python scripts/ch4/model_probe.py [--representation local] [--lr 0.1 0.02 ...] [--train 20000] [--test 3000]

The model learns on-line, as in a run, from ``--train`` experiences of ``probe_experiences`` (the scripted
teacher's move or, with probability 0.5, a random one; fresh layouts from seed 11), and is scored on ``--test``
others (seed 12) without learning from them. Per learning rate: the reinforcement prediction's mean absolute and
mean squared error, against predicting 0 everywhere; how many of the test's deaths (r = -1) and food (r = 0.4) it
predicts (a prediction below -0.5 counts as death, the threshold that ends a simulated play, and above 0.2 as
food) and how many it predicts wrongly; the mean |prediction| on the steps with r = 0; and the share of the 32
enemy units predicted wrong. Seeds 11 and 12 are development seeds; the runs' yardstick (``PROBE_SEED`` 4403) is
not used here.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from connrl.envs.survival import SurvivalEnv
from connrl.tasks.survival_models import LearnedModelConfig, LearnedSurvivalModel, probe_experiences


def score(model: LearnedSurvivalModel, test) -> dict:
    r = np.array([e[2] for e in test])
    pred = np.array([model.predict(x, a)[0] for x, a, _, _ in test])
    enemy = np.mean([model.prediction_error(x, a, rr, y)[1] for x, a, rr, y in test])
    death, food = pred < -0.5, pred > 0.2
    return {"abs": np.abs(pred - r).mean(), "mse": ((pred - r) ** 2).mean(),
            "death": (int(np.sum(death & (r < -0.5))), int(np.sum(death & (r >= -0.5)))),
            "food": (int(np.sum(food & (r > 0.2))), int(np.sum(food & (r <= 0.2)))),
            "zero_pred": np.abs(pred[r == 0]).mean(), "enemy": enemy}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--representation", choices=["global", "local"], default="local")
    ap.add_argument("--lr", nargs="+", type=float, default=[0.1, 0.05, 0.02, 0.01, 0.005])
    ap.add_argument("--train", type=int, default=20_000)
    ap.add_argument("--test", type=int, default=3_000)
    args = ap.parse_args()
    if not all(0 < v < math.inf for v in args.lr) or args.train < 1 or args.test < 1:
        ap.error("--lr must be numbers > 0, --train and --test 1 or more")
    train = probe_experiences(args.representation, 11, args.train)
    test = probe_experiences(args.representation, 12, args.test)
    r = np.array([e[2] for e in test])
    print(f"{args.representation} representation; {args.train:,} training experiences (seed 11), {args.test:,} test "
          f"(seed 12): {int(np.sum(r < -0.5))} deaths, {int(np.sum(r > 0.2))} food")
    print(f"predicting 0 everywhere: abs {np.abs(r).mean():.4f}, mse {(r ** 2).mean():.4f}")
    print(f"{'lr':>6} {'abs':>7} {'mse':>7}  {'deaths hit/false':>16}  {'food hit/false':>14}  {'|pred| at r=0':>13}  "
          f"{'enemy units wrong':>17}")
    env = SurvivalEnv(args.representation)
    env.reset(seed=0)
    for lr in args.lr:
        model = LearnedSurvivalModel(env, np.random.default_rng(0), LearnedModelConfig(lr=lr))
        for x, a, rr, y in train:
            model.learn(x, a, rr, y, False)
        s = score(model, test)
        death, food = "{}/{}".format(*s["death"]), "{}/{}".format(*s["food"])
        print(f"{lr:>6g} {s['abs']:>7.4f} {s['mse']:>7.4f}  {death:>16}  {food:>14}  "
              f"{s['zero_pred']:>13.3f}  {s['enemy']:>17.4f}", flush=True)


if __name__ == "__main__":
    main()
