"""What ``connrl run`` stores, read back with checks: run records, summaries, and the machine they came from.

Files are plain JSON and CSV written atomically (``connrl.storage``). Reading never trusts them: a record or
summary that is empty, truncated, binary, of the wrong shape or missing a key is *damaged*. A damaged run
record (or one whose CSV is gone) counts as not run, so ``connrl run`` redoes it; a damaged summary is
reported by name with how to rebuild it (``DamagedFile``).
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import os
import platform
import subprocess
from pathlib import Path

import numpy as np

from connrl.core.params import defaults
from connrl.experiments.spec import load_callable
from connrl.storage import (
    MAX_JSON_BYTES,
    MAX_NESTING,
    FileError,
    atomic_write_bytes,
    atomic_write_text,
    finite_float,
    json_problem,
    max_depth,
    read_limited,
    reject_constant,
    strict_json,
)

# run record key -> allowed JSON types
RECORD_KEYS = {"experiment": (str,), "variant": (str,), "seed": (int,), "params": (dict,), "metrics": (dict,),
               "curve_x": (list,), "curve_y": (list,), "wall_time_s": (int, float)}
SUMMARY_KEYS = {"experiment": (str,), "profile": (str,), "base_seed": (int,), "runs_per_variant": (int,),
                "variants": (dict,), "timing": (dict,), "environment": (dict,)}


class DamagedFile(ValueError):
    """A stored file that cannot be used; the message names it and says what is wrong."""

    def __init__(self, path, reason: str, fix: str = ""):
        self.path, self.reason = Path(path), reason
        self.fix = fix
        super().__init__(f"{path} is damaged ({reason})" + (f"; {fix}" if fix else ""))

    def __reduce__(self):  # raised in a worker process, it reaches the CLI as the same one line
        return type(self), (self.path, self.reason, self.fix)


def read_json(path) -> object:
    """The JSON in ``path``; ``DamagedFile`` when it is empty, binary, not JSON or not a regular file (a record is
    read by ``read_limited``: a link to a device or a FIFO neither hangs nor fills memory)."""
    try:
        raw = read_limited(path, MAX_JSON_BYTES, "run record")
    except FileError as exc:
        raise DamagedFile(path, exc.problem) from None
    if not raw.strip():
        raise DamagedFile(path, "empty")
    if max_depth(raw) > MAX_NESTING:
        raise DamagedFile(path, "nested too deeply to be ours")
    try:
        return json.loads(raw.decode("utf-8"), parse_constant=reject_constant, parse_float=finite_float)
    except UnicodeDecodeError:
        raise DamagedFile(path, "not text") from None
    except json.JSONDecodeError as exc:
        raise DamagedFile(path, f"not JSON: {json_problem(exc)}") from None
    except ValueError as exc:  # NaN / Infinity, or a number beyond a float: connrl writes strict JSON
        raise DamagedFile(path, str(exc)) from None
    except RecursionError:
        raise DamagedFile(path, "nested too deeply to be ours") from None


def _shape_problem(doc: object, keys: dict[str, tuple]) -> str | None:
    if not isinstance(doc, dict):
        return f"expected a JSON object, found {type(doc).__name__}"
    for key, types in keys.items():
        if key not in doc:
            return f"missing key {key!r}"
        v = doc[key]
        if not isinstance(v, types) or (isinstance(v, bool) and bool not in types):
            return f"{key!r} has the wrong type ({type(v).__name__})"
    return None


MAX_RUNS = 10_000  # per variant: far beyond any protocol; a larger count is a typo or a damaged file


def _number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def check_record(rec: object, job=None) -> str | None:
    """What is wrong with a run record (or, given its ``job``, why it is not that job's record), or None."""
    problem = _shape_problem(rec, RECORD_KEYS)
    if problem:
        return problem
    if len(rec["curve_x"]) != len(rec["curve_y"]):
        return "curve_x and curve_y differ in length"
    if not all(_number(v) for v in rec["curve_x"]) or not all(v is None or _number(v) for v in rec["curve_y"]):
        return "its curve holds something other than numbers (null marks a test with no value)"
    if not all(v is None or _number(v) for v in rec["metrics"].values()):
        return "a metric is neither a number nor null"
    if rec.get("diverged") is not None and not isinstance(rec["diverged"], dict):
        return "'diverged' is neither null nor an object"
    twin = rec.get("copy_of")
    if twin is not None and not (isinstance(twin, dict) and all(isinstance(twin.get(k), str) for k in
                                                                   ("experiment", "variant"))):
        return "'copy_of' does not name the experiment and variant of the run it copies"
    if job is not None:
        params = _as_stored(job.params)  # as stored: tuples become lists
        # a parameter declared after the record was written is the record's at its default (run_key's contract)
        stored = {**_stored_defaults(job.params_type), **rec["params"]}
        for key, want, have in (("experiment", job.experiment, rec["experiment"]), ("variant", job.variant,
                                 rec["variant"]), ("seed", job.seed, rec["seed"]), ("params", params, stored)):
            if have != want:
                return f"its {key} is not this run's" if key == "params" else \
                    f"its {key} is {have!r}, this run's is {want!r}"
    return None


def _as_stored(values: dict) -> dict:
    return json.loads(json.dumps(values, default=json_default))


@functools.cache
def _stored_defaults(params_type: str) -> dict:
    """The defaults of the parameter class ``module:Name`` as records store them, once per class (read only)."""
    return _as_stored(defaults(load_callable(params_type)))


def _csv_problem(path: Path) -> str | None:
    if not path.exists():
        return f"its CSV {path.name} is gone"
    try:
        text = read_limited(path, MAX_JSON_BYTES, "run CSV").decode("utf-8")
    except FileError as exc:
        return f"its CSV {path.name} {exc.problem}"
    except UnicodeDecodeError:
        return f"its CSV {path.name} is not text"
    return None if text.strip() else f"its CSV {path.name} is empty"


def load_record(path, job=None) -> tuple[dict | None, str | None]:
    """A finished run's record: ``(record, None)``; ``(None, None)`` if not run; ``(None, reason)`` if damaged
    (including a record of another run, and a CSV that is gone or not text), which the runner redoes."""
    p = Path(path).with_suffix(".json")
    if not p.exists():
        return None, None
    try:
        rec = read_json(p)
    except DamagedFile as exc:
        return None, exc.reason
    except OSError as exc:
        return None, f"unreadable: {exc.strerror or exc}"
    problem = check_record(rec, job) or _csv_problem(p.with_suffix(".csv"))
    return (None, problem) if problem else (rec, None)


def load_summary(path, name: str = "") -> dict:
    """A summary.json, checked; ``FileNotFoundError`` if absent, ``DamagedFile`` (saying how to rebuild it)."""
    fix = (f"run the `connrl run {name}` command that made it again (same --profile and --runs): finished runs "
           "are reused and the summary is rewritten") if name else "run the command that made it again"
    try:
        doc = read_json(path)
    except DamagedFile as exc:
        raise DamagedFile(path, exc.reason, fix) from None
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise DamagedFile(path, f"unreadable: {exc.strerror or exc}", fix) from None
    problem = _shape_problem(doc, SUMMARY_KEYS) or _summary_problem(doc, name)
    if problem:
        raise DamagedFile(path, problem, fix)
    return doc


QUANTITY_KEYS = {"per_run": (list,), "mean": (int, float, type(None)), "thesis": (int, float, type(None)),
                 "better": (str,)}


def _summary_problem(doc: dict, name: str) -> str | None:
    """Deeper checks of a summary whose top level is right: everything the show/plot/results code reads."""
    if name and doc["experiment"] != name:
        return f"it is the summary of {doc['experiment']!r}, not of {name!r}"
    if not 1 <= doc["runs_per_variant"] <= MAX_RUNS or doc["base_seed"] < 0:
        return "its run count or base seed is out of range"
    timing = doc["timing"]
    if not _number(timing.get("wall_time_s")) or not isinstance(timing.get("run_wall_time_s"), list):
        return "its timing is incomplete"
    copied = timing.get("run_copied")
    if copied is not None and not (isinstance(copied, list) and len(copied) == len(timing["run_wall_time_s"])
                                   and all(isinstance(c, bool) for c in copied)):
        return "its timing's run_copied is not a true/false per run"
    if not isinstance(doc["environment"].get("git_commit"), str | type(None)):
        return "its environment's git_commit is not text"
    for label, v in doc["variants"].items():
        if not isinstance(v, dict) or not isinstance(v.get("quantities"), dict):
            return f"variant {label!r} is not an object with quantities"
        if not isinstance(v.get("diverged", []), list) or not isinstance(v.get("seeds", []), list):
            return f"variant {label!r}: 'diverged' or 'seeds' is not a list"
        for qname, q in v["quantities"].items():
            problem = _shape_problem(q, QUANTITY_KEYS)
            if problem is None and not all(x is None or _number(x) for x in q["per_run"]):
                problem = "a per-run value is neither a number nor null"
            if problem is None and q.get("meets_thesis") not in (True, False, None):
                problem = "'meets_thesis' is neither true, false nor null"
            if problem:
                return f"variant {label!r}, quantity {qname!r}: {problem}"
    return None


def write_run_records(path: Path, record: dict, rows: list[dict]) -> None:
    buf = io.StringIO()
    if rows:
        keys = list(dict.fromkeys(k for r in rows for k in r))
        w = csv.DictWriter(buf, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    else:
        w = csv.writer(buf)
        w.writerow(["x", "y"])
        w.writerows(zip(record["curve_x"], record["curve_y"], strict=True))
    atomic_write_text(path.with_suffix(".csv"), buf.getvalue())
    # the .json is written last: its presence marks the run as finished
    atomic_write_text(path.with_suffix(".json"), strict_json(record, indent=1, default=json_default))


def write_copy(source: Path, record: dict, job) -> dict:
    """``job``'s records as a copy of the finished run at ``source`` (its ``record``), which had the same run
    function, parameters and seed: the CSV as it is, the record under ``job``'s experiment and variant with
    ``copy_of`` naming the run it copies (timing counts that run's time once). Returns the copy's record."""
    rec = dict(record, experiment=job.experiment, variant=job.variant,
               copy_of={"experiment": record["experiment"], "variant": record["variant"],
                        "record": "/".join(Path(source).parts[-5:]) + ".json"})  # EXP/runs/PROFILE-HASH/VARIANT/...
    path = Path(job.path)
    atomic_write_bytes(path.with_suffix(".csv"), Path(source).with_suffix(".csv").read_bytes())
    atomic_write_text(path.with_suffix(".json"), strict_json(rec, indent=1, default=json_default))
    return rec


def json_default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"cannot store {type(o).__name__} in JSON")


_ENV_INFO: dict | None = None


def environment_info() -> dict:
    global _ENV_INFO
    if _ENV_INFO is None:
        import gymnasium
        import numba

        import connrl

        try:
            commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5,
                                    cwd=Path(__file__).parent).stdout.strip() or None
        except (OSError, subprocess.SubprocessError):
            commit = None
        import llvmlite.binding as llvm

        # numba compiles its kernels for this CPU (or NUMBA_CPU_NAME), and fastmath lets the sums' order follow
        # its vector width: long learning runs are bit-identical on one CPU type, not across types
        _ENV_INFO = {"python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
                     "gymnasium": gymnasium.__version__, "connrl": connrl.__version__, "git_commit": commit,
                     "machine": platform.machine(), "cpus": os.cpu_count(),
                     "numba_cpu": os.environ.get("NUMBA_CPU_NAME") or llvm.get_host_cpu_name()}
    return _ENV_INFO
