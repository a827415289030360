"""Helpers of the fault-injection tests (issue 24): run the real CLI in a subprocess, damage files
deterministically, and check the one-line refusal every damaged file must get."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
PY = sys.executable
DEEP = 100_000  # nesting depth of the deep-JSON cases


def env() -> dict:
    e = dict(os.environ)
    e["PYTHONPATH"] = str(REPO) + (os.pathsep + e["PYTHONPATH"] if e.get("PYTHONPATH") else "")
    e["PYTHONDONTWRITEBYTECODE"] = "1"
    e["MPLBACKEND"] = "Agg"
    e.pop("PYTHONFAULTHANDLER", None)
    return e


MEMORY_CAP = 3 * 2**30  # issue 43's attacks must end under a 3 GB address-space cap


def _capped():  # in the child, before exec: a reader that fills memory fails fast instead of taking the machine
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))


def cli(args, cwd, timeout: float = 120, memory_cap: bool = False) -> subprocess.CompletedProcess:
    """``python -m connrl.cli ARGS`` in ``cwd`` (never the repo); with ``memory_cap`` under ``MEMORY_CAP``."""
    assert Path(cwd).resolve() != REPO
    return subprocess.run([PY, "-m", "connrl.cli", *map(str, args)], cwd=cwd, env=env(), capture_output=True,
                          text=True, timeout=timeout, preexec_fn=_capped if memory_cap else None)


def script(code: str, args, cwd, timeout: float = 120) -> subprocess.CompletedProcess:
    """A small Python script (``code``, run as a file so the cwd is not on sys.path) with ``args``."""
    path = Path(cwd) / "_fault_script.py"
    path.write_text(code)
    return subprocess.run([PY, str(path), *map(str, args)], cwd=cwd, env=env(), capture_output=True, text=True,
                          timeout=timeout)


def describe(proc) -> str:
    return f"exit code {proc.returncode}; stderr:\n{proc.stderr[-3000:]}\nstdout:\n{proc.stdout[-1000:]}"


def normal_exit(proc) -> None:
    """Not killed by a signal (negative code) and not a shell-style signal code (134 abort, 139 segfault...)."""
    assert proc.returncode >= 0 and proc.returncode not in (134, 136, 137, 139), \
        f"killed by a signal: {describe(proc)}"


def stderr_lines(proc) -> list[str]:
    return [line for line in proc.stderr.splitlines() if line.strip()]


def assert_refused(proc, names: str) -> str:
    """Exit 1 or 2, stderr exactly one non-empty line starting 'connrl: ' that contains ``names``, no traceback."""
    normal_exit(proc)
    assert "Traceback" not in proc.stderr, f"a traceback: {describe(proc)}"
    assert proc.returncode in (1, 2), f"not refused: {describe(proc)}"
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].strip(), f"stderr is not exactly one line: {describe(proc)}"
    assert lines[0].startswith("connrl: "), f"the line does not start with 'connrl: ': {describe(proc)}"
    assert names in lines[0], f"the line does not name {names!r}: {describe(proc)}"
    return lines[0]


def assert_noticed_or_refused(proc, names: str) -> None:
    """Either a refusal (``assert_refused``) or success (exit 0) whose stderr lines all start with 'connrl: ', one of
    them naming ``names`` (the notice that the damaged file was redone or left out)."""
    normal_exit(proc)
    assert "Traceback" not in proc.stderr, f"a traceback: {describe(proc)}"
    if proc.returncode != 0:
        assert_refused(proc, names)
        return
    lines = proc.stderr.splitlines()
    assert lines and all(line.startswith("connrl: ") for line in lines), \
        f"exit 0 without a one-line notice per problem: {describe(proc)}"
    assert any(names in line for line in lines), f"no notice names {names!r}: {describe(proc)}"


def strict_json(text: str):
    def refuse(token):
        raise ValueError(f"not strict JSON: bare {token}")

    return json.loads(text, parse_constant=refuse)


def snapshot(path: Path):
    """The bytes of a file, or of every file below a folder (the damaged thing must be left as it was)."""
    path = Path(path)
    if path.is_dir():
        return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}
    return path.read_bytes()


# -------------------------------------------------------------------------------------------- mutations

def truncate(data: bytes, fraction: float) -> bytes:
    return data[: int(len(data) * fraction)]


def flip_text(data: bytes, seed: int, n: int = 3) -> bytes:
    """XOR 0x80 at ``n`` seeded positions: an ASCII file stops being UTF-8 (never valid by luck)."""
    rng = np.random.default_rng(seed)
    b = bytearray(data)
    for i in rng.choice(len(b), size=n, replace=False):
        b[int(i)] ^= 0x80
    return bytes(b)


def flip_npz(data: bytes, seed: int, n: int = 4) -> bytes:
    """Flip ``n`` seeded bytes inside one member's stored data (so its CRC no longer matches: never valid by luck)."""
    rng = np.random.default_rng(seed)
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        infos = [i for i in z.infolist() if i.compress_size > 0]
    info = infos[int(rng.integers(len(infos)))]
    name_len = int.from_bytes(data[info.header_offset + 26: info.header_offset + 28], "little")
    extra_len = int.from_bytes(data[info.header_offset + 28: info.header_offset + 30], "little")
    start = info.header_offset + 30 + name_len + extra_len
    b = bytearray(data)
    for i in rng.choice(info.compress_size, size=min(n, info.compress_size), replace=False):
        b[start + int(i)] ^= 0xFF
    return bytes(b)


def deep_json(depth: int = DEEP) -> str:
    return "[" * depth + "]" * depth


def deep_value(depth: int = DEEP) -> str:
    """A JSON value nested ``depth`` deep, to put in place of one field."""
    return "[" * depth + "1" + "]" * depth


def rewrite_npz(path: Path, change) -> None:
    """Read every array of ``path``, let ``change(arrays)`` edit the dict, write it back as a plain npz."""
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    change(arrays)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    path.write_bytes(buf.getvalue())


def resign_agent(folder: Path) -> None:
    """Make agent.json's digest match a changed agent.npz, as an adversary editing both files would: the checks of
    the arrays themselves, not the digest, must then refuse them."""
    import hashlib

    meta = Path(folder) / "agent.json"
    doc = json.loads(meta.read_text())
    doc["npz_sha256"] = hashlib.sha256((Path(folder) / "agent.npz").read_bytes()).hexdigest()
    meta.write_text(json.dumps(doc, indent=1))
