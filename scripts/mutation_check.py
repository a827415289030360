"""Issue 46's mutation check, by hand: apply each mutant, run the tests of the mutated module's own folder, revert.

    python scripts/mutation_check.py [INDEX ...]

Prints CAUGHT or MISSED per mutant (every one should be CAUGHT). Each mutant must match its file exactly once; the
file is put back even when the run is interrupted. Run from the repository's root, with its venv."""

import subprocess
import sys
from pathlib import Path

K, P, X = "connrl/nets/kernels.py", "connrl/core/params.py", "connrl/experiments/"
MUTANTS = [  # (file, text, mutated text, the tests of its folder)
    (K, "            used += 1\n            changed = a\n        if repair != 0:",
     "            used += 2\n            changed = a\n        if repair != 0:", "tests/nets"),
    (K, "(1.0 - lam_t) * u + lam_t * e_next)\n    return clip if has_clip and e > clip else e\n\n\n@numba.njit(cache"
        "=True, fastmath=True",
     "(1.0 - lam_t) * u + lam_t * u)\n    return clip if has_clip and e > clip else e\n\n\n@numba.njit(cache"
        "=True, fastmath=True", "tests/nets"),
    (K, "lam if (t < n - 1 and weights[t + 1] > 0.0) else 0.0", "lam if (t < n - 1) else 0.0", "tests/nets"),
    (K, "return (i, s0, s1, x0, x0 + (s1 - s0) + 1), (replay[0], replay[1], thresholds[k], replay[3], replay[4])",
     "return (i, s0, s1, x0, x0 + (s1 - s0) + 1), (replay[0], replay[1], replay[2], replay[3], replay[4])",
     "tests/nets"),
    (P, "changed = {k: v for k, v in values.items() if k not in plain or v != plain[k]}",
     "changed = {k: v for k, v in values.items() if k not in plain}", "tests/core"),
    (P, "if rng is not None and v is not None and not _RANGES[rng][0](v):",
     "if rng is not None and v is not None and _RANGES[rng][0](v) is None:", "tests/core"),
    (P, "        if f is not None and f.metadata.get(what) is not None:\n            return f.metadata[what]",
     "        if f is not None and f.metadata.get(what) is not None:\n            return f.metadata[what]\n"
     "        return None", "tests/core"),
    ("connrl/core/replay.py", "return replay_settings(self.lam, self.temperature, self.p_threshold, self.clip)",
     "return replay_settings(self.lam, self.p_threshold, self.temperature, self.clip)", "tests/core"),
    (X + "store.py", 'stored = {**_stored_defaults(job.params_type), **rec["params"]}', 'stored = rec["params"]',
     "tests/experiments"),
    (X + "runner.py", "if found and all(rec is not None and not fields <= set(rec[\"params\"]) for rec, _ in found):",
     "if found and all(rec is not None for rec, _ in found):", "tests/experiments"),
    (X + "registry.py", "return tuple(sorted(found, key=lambda m: (m.CHAPTER, m.__name__)))",
     "return tuple(sorted(found, key=lambda m: (m.CHAPTER, m.__name__)))[:-1]", "tests/experiments"),
    ("connrl/report/page.py",
     "    parts += _plain_sections(out, doc, specs, [n for n in specs if n not in covered], covered)\n", "",
     "tests/report"),
    ("connrl/tasks/robot.py", "gamma=p.gamma, lam=p.lam, online=p.online",
     "gamma=p.gamma, lam=p.gamma, online=p.online", "tests/tasks"),
    ("connrl/own/settings.py", 'SETTINGS_DIR = Path(__file__).parents[1] / "data" / "hyperparams"',
     'SETTINGS_DIR = Path(__file__).parents[0] / "data" / "hyperparams"', "tests/own"),
    (K, "                n += 1\n        return 1.0 / n", "                n += 1\n        return 1.0", "tests/nets"),
    (K, "            s += w[row, k] * math.exp((q[k] - top) / temperature)",
     "            s += math.exp((q[k] - top) / temperature)", "tests/nets"),
    ("connrl/core/training.py", "        if callbacks.on_trial_end(agent, stats) is False:\n            break",
     "        if callbacks.on_trial_end(agent, stats) is False:\n            pass", "tests/core"),
    ("connrl/core/training.py", "stats = play(k, None if steps is None else steps - done)", "stats = play(k, None)",
     "tests/core"),
    ("connrl/core/divergence.py", "raise Diverged(self.trials, problem)", "raise Diverged(self.trials - 1, problem)",
     "tests/core"),
    ("connrl/core/boltzmann_kernel.py", "p[k] = w[k] * p[k] if w[k] > 0 else 0.0", "p[k] = p[k] if w[k] > 0 else 0.0",
     "tests/core"),
    (X + "protocol.py", "(self.last and n == self.trials)", "(n == self.trials)", "tests/experiments"),
    ("connrl/tasks/recharge_play.py", "goal = docked if b == 0 else (b == 1 and not collided and moved)",
     "goal = docked if b == 0 else (b == 1 and not collided)", "tests/tasks"),
    ("connrl/tasks/recharge_play.py", "obs[48:72], obs[72:76], obs[76:84] = dk[0:48], dp[24:48], dk[48:52]",
     "obs[48:72], obs[72:76], obs[76:84] = dk[0:48], dp[0:24], dk[48:52]", "tests/tasks"),
]


def main() -> None:
    for i in [int(x) for x in sys.argv[1:]] or range(len(MUTANTS)):
        f, old, new, folder = MUTANTS[i]
        p = Path(f)
        s = p.read_text()
        if s.count(old) != 1:
            raise SystemExit(f"mutant {i}: its text occurs {s.count(old)} times in {f}, not once")
        p.write_text(s.replace(old, new))
        try:
            r = subprocess.run([sys.executable, "-m", "pytest", "-x", "-n", "2", folder], capture_output=True,
                               text=True)
            last = r.stdout.strip().splitlines()[-1][:100]
            print(i, f, "CAUGHT" if r.returncode else "MISSED", last, flush=True)
        finally:
            p.write_text(s)


if __name__ == "__main__":
    main()
