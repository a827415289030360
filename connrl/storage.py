"""Files connrl writes and reads: atomic writes of plain formats (JSON, CSV, NPZ without pickle) and the checked
readers every file format builds on.

Writing: a reader never sees half a file. The temporary file is created exclusively under an unpredictable name
(``tempfile.mkstemp``: ``O_CREAT | O_EXCL``, so a link planted beside the target is never followed), and it is
removed when the write fails (a full disk leaves nothing behind).

Reading never trusts a file: ``read_json`` bounds its size and nesting and refuses what is not JSON, the
``check_*`` helpers bound every number, index and shape, and all of them raise ``FileError``, a ``ValueError``
whose message is one line naming the file, the field and what is allowed. Code that hands arrays to compiled
kernels checks them here first.
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import math
import os
import re
import stat
import tempfile
import zipfile
from pathlib import Path

import numpy as np

# Limits on what a file may hold, sized to what reading it may cost in memory (a parsed JSON or CSV file takes up to
# ~10-30x its bytes as Python objects), not only to what connrl writes (its largest JSON files are under 1 MiB).
MAX_JSON_BYTES = 32 * 2**20
MAX_NPZ_BYTES = 512 * 2**20  # an archive's bytes, and separately the bytes its arrays unpack to
MAX_NESTING = 32  # connrl's JSON files nest at most ~6 levels


@contextlib.contextmanager
def run_lock(folder: Path, other: str = "--out"):
    """Hold ``FOLDER/.connrl-run.lock`` while a run writes there: a second ``connrl run``, ``train`` or ``tune`` into
    the same folder is refused at once (``BlockingIOError`` in one line; ``other`` names the option that picks another
    folder) instead of computing twice or losing one writer's work. The lock is the OS's (released even when the
    holder is killed); where ``fcntl`` is missing (Windows) there is none."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    fd = os.open(folder / ".connrl-run.lock", os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            then = " (its finished runs are then reused)" if other == "--out" else ""
            raise BlockingIOError(errno.EWOULDBLOCK, f"another connrl command is writing to {folder}; wait for it "
                                  f"to finish{then} or give another {other}") from None
        yield
    finally:
        os.close(fd)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_FILE_MODE = 0o666 & ~_umask()  # what open() would have given a new file


class FileError(ValueError):
    """A file connrl cannot use; ``str()`` is one line: ``PATH: [FIELD: ]what is wrong; what is allowed``."""

    def __init__(self, path, problem: str, field: str | None = None):
        self.path, self.field, self.problem = Path(path), field, problem
        super().__init__(f"{path}: {field + ': ' if field else ''}{problem}")

    def __reduce__(self):  # raised in a worker process, it reaches the CLI as the same one line
        return type(self), (self.path, self.problem, self.field)


# --------------------------------------------------------------------------------------------------- writing

def atomic_write_bytes(path, data: bytes) -> None:
    atomic_write_files({path: data})


def atomic_write_files(files: dict) -> None:
    """Write several files as one: every temporary file is written first, then each is moved into place, so a
    failure while writing (a full disk, Ctrl-C) leaves every old file as it was and no temporary file behind."""
    temps = []
    try:
        for path, data in files.items():
            path = Path(path)
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            temps.append((tmp, path))
            try:
                os.fchmod(fd, _FILE_MODE)  # mkstemp's 0600 would hide results from the user's group
                with os.fdopen(fd, "wb") as f:
                    f.write(data)
                    f.flush()
                    os.fsync(f.fileno())
            except OSError as exc:  # a full disk names no file of its own: name the one being written
                raise OSError(exc.errno, exc.strerror, str(path)) from None
        with _signals_held(len(temps) > 1):  # a signal between two moves would pair files of two saves
            for tmp, path in temps:
                os.replace(tmp, path)
    except BaseException:
        for tmp, _ in temps:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        raise


@contextlib.contextmanager
def _signals_held(hold: bool):
    """SIGINT and SIGTERM held back until the block ends, then delivered to the handlers they were meant for (main
    thread only: Python runs signal handlers there, whichever thread the OS gave the signal to)."""
    import signal
    import threading

    sigs = (signal.SIGINT, signal.SIGTERM)
    if not hold or threading.current_thread() is not threading.main_thread() or any(
            signal.getsignal(x) is None for x in sigs):  # a handler set outside Python cannot be put back
        yield
        return
    pending: list[int] = []
    old = {x: signal.signal(x, lambda signum, frame: pending.append(signum)) for x in sigs}
    try:
        yield
    finally:
        for x, handler in old.items():
            signal.signal(x, handler)
        if pending:
            signal.raise_signal(pending[0])


def npz_bytes(**arrays: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **{k: np.asarray(v) for k, v in arrays.items()})
    return buf.getvalue()


def atomic_write_text(path, text: str) -> None:
    atomic_write_bytes(path, text.encode())


def strict_json(doc, **kwargs) -> str:
    """``json.dumps`` that any JSON parser reads: a non-finite float becomes null (never a bare NaN)."""
    return json.dumps(_finite_or_none(doc), allow_nan=False, **kwargs)


def _finite_or_none(v):
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, np.floating):
        return float(v) if np.isfinite(v) else None
    if isinstance(v, dict):
        return {k: _finite_or_none(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_finite_or_none(x) for x in v]
    if isinstance(v, np.ndarray):
        return _finite_or_none(v.tolist())
    return v


def atomic_save_npz(path, **arrays: np.ndarray) -> None:
    """NPZ holding numeric arrays only; read it back with ``read_npz`` (never pickle)."""
    atomic_write_bytes(path, npz_bytes(**arrays))


def check_writable_dir(path) -> None:
    """Make sure ``path`` is (or can become) a folder we can write in, before any work is done; ``OSError``
    with a plain reason otherwise."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(f"{path} is a file, not a folder")
    path.mkdir(parents=True, exist_ok=True)
    fd, probe = tempfile.mkstemp(prefix=".connrl-write-test-", dir=path)
    os.close(fd)
    os.unlink(probe)


# --------------------------------------------------------------------------------------------------- reading

def reject_constant(name: str):
    """``json.loads``'s ``parse_constant`` for strict JSON: NaN / Infinity are refused (ValueError)."""
    raise ValueError(f"{name} is not JSON (JSON has no NaN or Infinity)")


def finite_float(text: str) -> float:
    """``json.loads``'s ``parse_float`` refusing a number beyond a 64-bit float (ValueError)."""
    v = float(text)
    if not math.isfinite(v):  # 1e400 parses as inf
        raise ValueError(f"the number {text[:40]} is too large for a float")
    return v


def read_limited(path, max_bytes: int, what: str = "file") -> bytes:
    """The bytes of ``path``, trusting nothing the file says about itself: it must be a regular file, checked before
    it is opened (a device is never opened: opening one can act, e.g. a tape rewinds) and again on the opened
    descriptor (the same file, still regular); it is opened without blocking, so a FIFO cannot hang us; and at most
    ``max_bytes + 1`` bytes are ever read, whatever size it reports (a /proc file reports 0). FileError (one line)
    otherwise."""
    path = Path(path)
    try:
        before = os.stat(path)
    except FileNotFoundError:
        raise FileError(path, f"no such {what}") from None
    except OSError as exc:
        raise FileError(path, f"cannot read the {what} ({exc.strerror or exc})") from None
    _check_regular(path, before, what, max_bytes)
    flags = (os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
             | getattr(os, "O_BINARY", 0))
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise FileError(path, f"no such {what}") from None
    except OSError as exc:
        raise FileError(path, f"cannot read the {what} ({exc.strerror or exc})") from None
    try:
        st = os.fstat(fd)
        if (st.st_dev, st.st_ino) != (before.st_dev, before.st_ino):
            raise FileError(path, f"changed while it was being opened; a {what} must stay put while it is read")
        _check_regular(path, st, what, max_bytes)
        data = bytearray()
        while len(data) <= max_bytes:  # the size stat gave may be wrong (a file still growing, /proc)
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - len(data)))
            if not chunk:
                break
            data += chunk
        if len(data) > max_bytes:
            raise FileError(path, f"is more than {max_bytes} bytes; a {what} is at most {max_bytes}")
        return bytes(data)
    except OSError as exc:
        raise FileError(path, f"cannot read the {what} ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def _check_regular(path, st, what: str, max_bytes: int) -> None:
    if stat.S_ISDIR(st.st_mode):
        raise FileError(path, f"is a folder; a {what} was expected")
    if not stat.S_ISREG(st.st_mode):
        raise FileError(path, f"is not a regular file (a device, pipe or socket); a {what} is a regular file")
    if st.st_size > max_bytes:
        raise FileError(path, f"is {st.st_size} bytes; a {what} is at most {max_bytes}")


def read_limited_text(path, max_bytes: int, what: str = "file") -> str:
    """``read_limited`` decoded as UTF-8; FileError naming the file when it is not."""
    try:
        return read_limited(path, max_bytes, what).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileError(path, f"is not UTF-8 text (byte {exc.start}); a {what} is UTF-8 text") from None


def read_json(path, what: str = "file", max_bytes: int = MAX_JSON_BYTES, constants: bool = False):
    """The JSON document in ``path`` (read by ``read_limited``); FileError (one line) when it is missing, a folder,
    not a regular file, too large, not UTF-8, not JSON, nested more than MAX_NESTING deep, or (unless
    ``constants``) holds NaN / Infinity literals."""
    path = Path(path)
    raw = read_limited(path, max_bytes, what)
    if not raw.strip():
        raise FileError(path, f"is empty; a {what} holds JSON")
    depth = max_depth(raw)
    if depth > MAX_NESTING:
        raise FileError(path, f"nests {depth} levels deep; a {what} nests at most {MAX_NESTING}")
    try:
        return json.loads(raw.decode("utf-8"), parse_constant=None if constants else reject_constant,
                          parse_float=finite_float)
    except UnicodeDecodeError:
        raise FileError(path, f"is not text; a {what} holds JSON") from None
    except json.JSONDecodeError as exc:
        raise FileError(path, f"is not JSON ({json_problem(exc)}); a {what} holds JSON") from None
    except (ValueError, RecursionError) as exc:
        raise FileError(path, f"{exc}") from None


def json_problem(exc: json.JSONDecodeError) -> str:
    """A JSON error in our words: "Unterminated string starting at: line 1 column 5 (char 4)" would read "starting at
    at line 1" with a position appended, so the position is given once, as line and column."""
    return f"{exc.msg.removesuffix(' starting at')} at line {exc.lineno}, column {exc.colno}"


# a string (escapes inside it, an unterminated one running to the end: possessive, so never rescanned) or a bracket
_JSON_TOKENS = re.compile(rb'"(?:[^"\\]++|\\.)*+"?|[\[\]{}]', re.S)


def max_depth(raw: bytes) -> int:
    """How deep brackets nest outside strings (a bound checked before parsing: the parser recurses). One pass, linear
    in the file's length whatever it holds."""
    depth = best = 0
    for m in _JSON_TOKENS.finditer(raw):
        c = m.group()[:1]
        if c in (b"[", b"{"):
            depth += 1
            best = max(best, depth)
        elif c in (b"]", b"}"):
            depth -= 1
    return best


def read_npz(path, what: str = "array file", max_bytes: int = MAX_NPZ_BYTES) -> dict[str, np.ndarray]:
    """Every array of an NPZ archive (``npz_arrays`` on its bytes); FileError (one line) otherwise."""
    return npz_arrays(read_limited(path, max_bytes, what), path, what, max_bytes)


NPZ_DTYPES = "biuf"  # bool, integers, floats: what connrl's archives hold


def npz_arrays(raw: bytes, path, what: str = "array file", max_bytes: int = MAX_NPZ_BYTES) -> dict[str, np.ndarray]:
    """The arrays of the NPZ archive ``raw`` (read from ``path``), trusting nothing it says about itself: NumPy's
    loader is never called (no pickle, and no allocation sized by a header's claimed shape); each member must be a
    .npy array of numbers whose header's shape and dtype account exactly for the bytes the member holds, and the
    members together unpack to at most ``max_bytes``."""
    fmt = np.lib.format
    if not raw.startswith(b"PK"):
        kind = "a single .npy array" if raw.startswith(b"\x93NUMPY") else "not an .npz archive"
        raise FileError(path, f"is {kind}; the {what} must be an .npz archive of numeric arrays")
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            infos = zf.infolist()
            total = sum(i.file_size for i in infos)
            if total > max_bytes:
                raise FileError(path, f"unpacks to {total} bytes; a {what} unpacks to at most {max_bytes}")
            out = {}
            for info in infos:
                name = info.filename.removesuffix(".npy")
                if name == info.filename or name in out:
                    raise FileError(path, f"holds {info.filename[:60]!r}; a {what} holds .npy arrays only")
                with zf.open(info) as f:
                    version = fmt.read_magic(f)
                    if version not in ((1, 0), (2, 0)):
                        raise FileError(path, f"uses .npy format {version}; connrl reads 1.0 and 2.0", name)
                    shape, fortran, dtype = (fmt.read_array_header_1_0 if version == (1, 0)
                                             else fmt.read_array_header_2_0)(f)
                    if dtype.hasobject or dtype.kind not in NPZ_DTYPES or dtype.fields is not None:
                        raise FileError(path, f"holds {dtype} data (Python objects, strings or records); a {what} "
                                              "holds numbers only", name)
                    nbytes = math.prod(shape) * dtype.itemsize
                    if f.tell() + nbytes != info.file_size:
                        raise FileError(path, f"its header claims shape {shape} ({nbytes} bytes) but it holds "
                                              f"{info.file_size - f.tell()}", name)
                    data = f.read(nbytes)
                out[name] = np.frombuffer(data, dtype=dtype).reshape(shape, order="F" if fortran else "C").copy()
            return out
    except FileError:
        raise
    except MemoryError:
        raise FileError(path, f"is too large to load; a {what} unpacks to at most {max_bytes} bytes") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError, NotImplementedError) as exc:
        detail = (str(exc).splitlines() or [""])[0][:120]
        raise FileError(path, f"is not a readable {what} ({type(exc).__name__}: {detail}); it must be an .npz "
                              "archive of numeric arrays") from None


def shown(v) -> str:
    """``repr(v)`` for a message, short: an integer too long to print is described (repr of one beyond 4300 digits
    raises), anything else cut at 40 characters."""
    if isinstance(v, int) and not isinstance(v, bool) and v.bit_length() > 128:
        return f"an integer of {v.bit_length()} bits"
    try:
        r = repr(v)
    except ValueError:  # a container holding such an integer
        return f"a {type(v).__name__} holding an integer too long to show"
    return r if len(r) <= 40 else r[:37] + "..."


def check_number(path, field: str, v, low: float = -math.inf, high: float = math.inf, *, integer: bool = False,
                 low_open: bool = False) -> float | int:
    """A JSON number (not a bool) that is finite, whole if ``integer``, and in [low, high] (or (low, high])."""
    kind = "a whole number" if integer else "a finite number"
    ok = isinstance(v, int | float) and not isinstance(v, bool) and (not integer or isinstance(v, int))
    if ok and isinstance(v, float):
        ok = math.isfinite(v)
    in_range = ok and (low < v if low_open else low <= v) and v <= high
    if not in_range:
        bounds = " and ".join(([f"{'>' if low_open else '>='} {low:g}"] if low > -math.inf else [])
                              + ([f"<= {high:g}"] if high < math.inf else []))
        raise FileError(path, f"is {shown(v)}; it must be {kind}{' ' + bounds if bounds else ''}", field)
    return v


def check_array(path, field: str, a, shape: tuple | None = None, *, low: float = -math.inf, high: float = math.inf,
                integer: bool = False) -> np.ndarray:
    """A numeric array of ``shape`` (None: any; -1 in it: any length there) whose entries are finite and in
    [low, high] (whole numbers if ``integer``), as float64 (int64 if ``integer``)."""
    a = np.asarray(a)
    if a.dtype.kind not in ("i", "u", "f", "b") or (integer and a.dtype.kind == "f"):
        raise FileError(path, f"holds {a.dtype} data; it must hold {'integers' if integer else 'numbers'}", field)
    if shape is not None and (len(a.shape) != len(shape) or any(s != -1 and s != n for s, n in zip(shape, a.shape,
                                                                                                   strict=True))):
        want = "(" + ", ".join("any" if s == -1 else str(s) for s in shape) + ")"
        raise FileError(path, f"has shape {a.shape}; it must have shape {want}", field)
    if a.size:
        if a.dtype.kind == "f" and not np.isfinite(a).all():
            raise FileError(path, "holds NaN or infinite values; it must hold finite numbers", field)
        lo, hi = a.min(), a.max()
        if lo < low or hi > high:
            raise FileError(path, f"holds values in [{lo:g}, {hi:g}]; they must lie in [{low:g}, {high:g}]", field)
    return a.astype(np.int64 if integer else np.float64)
