"""Diagnostic harness: a ``connrl.experiments.robot.RobotRun`` (the steps ``run_robot`` takes, in its
random-number order) with hooks for looking inside."""

import numpy as np

from connrl.experiments.robot import RobotParams, RobotRun
from connrl.experiments.spec import override
from connrl.tasks.robot import make_taught_lessons


class Run:
    def __init__(self, seed, **over):
        self.trunc_terminal = bool(over.pop("trunc_terminal", 0))
        lesson_seed = over.pop("lesson_seed", None)
        lesson_fn = over.pop("lesson_fn", None)
        p = override(RobotParams(), over, "harness")
        self.p = p
        self.run = RobotRun(p, np.random.default_rng(seed))
        self.env, self.test_env, self.agent = self.run.env, self.run.test_env, self.run.agent
        self.tests, self.test_seeds = self.run.tests, self.run.test_seeds
        if lesson_seed is not None or lesson_fn is not None:  # drawing them uses no run random numbers
            if lesson_fn is not None:
                import importlib

                mod, fn = lesson_fn.split(":")
                lessons = getattr(importlib.import_module(mod), fn)(p.lessons, int(lesson_seed or 0))
            else:
                lessons = make_taught_lessons(p.task, p.lessons, seed=int(lesson_seed))
            self.agent.book.taught = []
            self.agent.add_taught_lessons(lessons)
        self.k = 0
        self.train_log = []

    def train(self, n, on_step=None):
        for _ in range(n):
            if self.trunc_terminal:
                self._patch()
            st = self.run.train(self.k, on_step=on_step)
            self.train_log.append((st.steps, st.total_reward, bool(st.info.get("success"))))
            self.k += 1

    def _patch(self):
        """Variant: a given-up (timed-out) lesson ends in a state of utility 0, on-line and in replay."""
        if getattr(self, "_patched", False):
            return
        self._patched = True
        book = self.agent.book
        orig = book.close_trial

        def close_trial():
            if book.ended[1]:
                book.ended = (True, False)
            return orig()

        book.close_trial = close_trial
        ag = self.agent
        orig_obs = ag.observe

        def observe(a, r, y, term, trunc, info=None):
            return orig_obs(a, r, y, term or trunc, trunc, info)

        ag.observe = observe

    def perf(self):
        return self.run.test()

    def detailed_test(self):
        """Greedy tests with per-step records: obs, action, reward, collision, q."""
        out = []
        ag, env = self.agent, self.test_env
        for start, s in zip(self.tests, self.test_seeds, strict=False):
            obs, info = env.reset(seed=int(s), options={"start": start})
            ag.begin_trial(obs, info, trial=0, learning=False)
            recs = []
            for _t in range(self.p.max_steps):
                q = ag.q.values(np.asarray(obs, dtype=np.float64))
                a = ag.act(obs, info, greedy=True)
                nobs, r, term, trunc, info = env.step(a)
                recs.append(
                    dict(
                        obs=np.asarray(obs, float),
                        a=a,
                        r=r,
                        q=q,
                        coll=info["collision"],
                        side=info["collision_side"],
                        pose=info["pose"],
                    )
                )
                obs = nobs
                if term or trunc:
                    break
            ag.end_trial()
            out.append(dict(recs=recs, success=bool(info.get("success")), trace=env.trace))
        return out


def curve(seed, trials, every=10, **over):
    r = Run(seed, **over)
    xs, ys = [0], [r.perf()]
    while r.k < trials:
        r.train(every)
        xs.append(r.k)
        ys.append(r.perf())
    return xs, ys
