"""What the Python commands fit, sweep and view share: the C++ commands' rules for files
(include/featherdrive/io/files.hpp, tools/cli_common.cpp), numbers and arguments.

Inputs are read by the C++ reader (fd.read_input_file): regular files of at most
fd.MAX_INPUT_BYTES, a FIFO, a device or a folder refused before a byte is read. Text is UTF-8 (a
byte order mark at its start is skipped); a CSV error names the file and the line. Outputs are
checked before any work (check_outputs: no output may be an input or another output, nor an
existing file that is not regular) and written whole through a temporary file beside them, with
the replaced file's permissions or 0666 less the umask (as AtomicFile).
"""

import csv
import io
import math
import numbers
import os
import re
import reprlib
import stat
import tempfile

import featherdrive as fd

__all__ = ["read_bytes", "read_text", "read_csv", "load_scene", "decimal", "is_decimal",
           "scene_inputs", "check_outputs", "write_atomically", "integer", "client", "path",
           "optional_text"]

_BOM = b"\xef\xbb\xbf"


def read_bytes(path, what="the file"):
    """The file's bytes; ValueError (fd.InputError) naming it for a file the commands refuse."""
    return fd.read_input_file(os.fspath(path), what)


def read_text(path, what="the file"):
    """The file as UTF-8 text, a leading byte order mark skipped; ValueError naming the file, the
    line and the byte offset of the first byte that is not UTF-8."""
    data = read_bytes(path, what)
    start = len(_BOM) if data.startswith(_BOM) else 0
    try:
        return data[start:].decode("utf-8")
    except UnicodeDecodeError as exc:
        offset = start + exc.start
        line = data.count(b"\n", 0, offset) + 1
        raise ValueError(f"{os.fspath(path)}: line {line}, byte offset {offset}: byte "
                         f"0x{data[offset]:02x} is not UTF-8 ({what} must be UTF-8 text)") from None


def read_csv(path, what="the CSV"):
    """The rows of a CSV file (read_text); ValueError naming the file and the line (and the
    column of a field longer than csv's limit) for what the csv module refuses."""
    text = read_text(path, what)
    reader = csv.reader(io.StringIO(text, newline=""))
    rows = []
    try:
        for row in reader:
            rows.append(row)
    except csv.Error as exc:
        where = f"line {reader.line_num}"
        limit = csv.field_size_limit()
        lines = text.splitlines()
        if "field limit" in str(exc) and 0 < reader.line_num <= len(lines):
            fields = lines[reader.line_num - 1].split(",")
            long = [k for k, f in enumerate(fields) if len(f) > limit]
            if long:
                k = long[0]
                name = f" ({rows[0][k]})" if rows and k < len(rows[0]) else ""
                where += f", column {k + 1}{name}"
                exc = f"a field of {len(fields[k])} characters (at most {limit})"
        raise ValueError(f"{os.fspath(path)}: {where}: {exc}") from None
    return rows


def load_scene(path):
    """fd.Scene of a scene file read by read_text ("FILE: cannot open the scene: ...")."""
    return fd.parse_scene(read_text(path, "the scene"), os.fspath(path))


def scene_inputs(scene):
    """[(what, path)] of the files a loaded scene was read from: the scene and its robot's."""
    inputs = [("the scene", os.fspath(scene.path)),
              ("the scene's model", os.fspath(scene.model_path))]
    # The files the robot's model read besides itself (MJCF <include>s and meshes) are inputs too.
    inputs += [("a file of the scene's model", os.fspath(p))
               for p in getattr(scene.robot, "input_files", ())]
    return inputs


def _identity(path):
    """What a path names (as file_identity in C++): the file's device and inode, or for a path
    that does not exist yet its folder's and its name."""
    try:
        st = os.stat(path)
        return (st.st_dev, st.st_ino, "")
    except OSError:
        pass
    try:
        st = os.stat(os.path.dirname(path) or ".")
        return (st.st_dev, st.st_ino, os.path.basename(path))
    except OSError:
        return (0, 0, os.path.realpath(path))


def check_outputs(outputs, inputs):
    """outputs [(option, path)], inputs [(what, path)], None paths left out: ValueError in one
    line for an output that exists and is not a regular file, is one of the inputs, or is also
    an earlier output. Call it before any work, so that a refused run changes nothing."""
    seen = []
    inputs = [(what, os.fspath(p)) for what, p in inputs if p is not None]
    for option, path in outputs:
        if path is None:
            continue
        path = os.fspath(path)
        try:
            if not stat.S_ISREG(os.stat(path).st_mode):
                raise ValueError(f"{option} {path}: is not a regular file; refusing to replace it")
        except FileNotFoundError:
            pass
        except OSError as exc:
            raise ValueError(f"{option} {path}: {exc.strerror}") from None
        identity = _identity(path)
        for what, p in inputs:
            if _identity(p) == identity:
                raise ValueError(f"{option} {path}: is {what} ({p}, an input of this run); "
                                 "refusing to overwrite it")
        for other, p in seen:
            if _identity(p) == identity:
                raise ValueError(f"{option} {path}: is also {other}; two outputs cannot share a "
                                 "file")
        seen.append((option, path))


def _umask():
    """The process's umask, read without changing it (os.umask would race with other threads)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    return 0o022


def write_atomically(path, write):
    """Writes an output whole or not at all: write(temporary path) fills a temporary file beside
    path, which then gets path's permissions (0666 less the umask for a new file), is synced and
    renamed over path. The temporary is removed when anything fails."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    handle, tmp = tempfile.mkstemp(dir=folder, prefix=f".{os.path.basename(path)}.",
                                   suffix=".tmp")
    os.close(handle)
    try:
        write(tmp)
        try:
            mode = stat.S_IMODE(os.stat(path).st_mode)
        except FileNotFoundError:
            mode = 0o666 & ~_umask()
        os.chmod(tmp, mode)
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


# ---- numbers and arguments -------------------------------------------------------------------

# A decimal number as the C++ readers take it: sign, digits with an optional point, exponent.
# Python's float() also takes 1_0, " 1", "infinity" and "nan": none of them is a number here.
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def is_decimal(text):
    """Whether text spells a decimal number (_DECIMAL)."""
    return _DECIMAL.fullmatch(text) is not None


def decimal(text, where):
    """The finite number a CSV field spells; ValueError "WHERE = 'TEXT': not a number" (or
    "WHERE = TEXT: must be finite" for nan, inf and what overflows) otherwise."""
    if not is_decimal(text):
        if text.strip().lstrip("+-").lower() in ("nan", "inf", "infinity"):
            raise ValueError(f"{where} = {text}: must be finite")
        raise ValueError(f"{where} = {text!r}: not a number (a decimal number is expected)")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{where} = {text}: must be finite")
    return value


# A Batch's most threads (Batch::kMaxThreads; 0 is every core).
MAX_THREADS = 4096

_short = reprlib.Repr()
_short.maxstring = 40
_short.maxother = 40


def integer(value, name, lo, hi, none=False):
    """An integer argument in [lo, hi] (None too when none): TypeError for a bool, a float or
    another type, ValueError out of range, each naming the argument and its value."""
    if value is None and none:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} = {_short.repr(value)}: must be an integer"
                        f"{' or None' if none else ''}, not {type(value).__name__}")
    if not lo <= value <= hi:
        raise ValueError(f"{name} = {value}: must be in [{lo}, {hi}]")
    return int(value)


def client(value):
    """A dask.distributed Client or None: TypeError for anything without its map, gather,
    cancel and scheduler_info."""
    if value is not None and not all(callable(getattr(value, a, None))
                                     for a in ("map", "gather", "cancel", "scheduler_info")):
        raise TypeError(f"client = {_short.repr(value)}: must be a distributed.Client or None, "
                        f"not {type(value).__name__}")
    return value


def path(value, name, none=False):
    """A path argument (str or os.PathLike; None too when none): TypeError otherwise."""
    if value is None and none:
        return None
    if isinstance(value, bytes) or not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name} = {_short.repr(value)}: must be a path (str or os.PathLike)"
                        f"{' or None' if none else ''}, not {type(value).__name__}")
    if os.fspath(value) == "":
        raise ValueError(f"{name} = '': an empty path")
    return value


def optional_text(value, name):
    """A str argument or None: TypeError naming it otherwise."""
    if value is not None and not isinstance(value, str):
        raise TypeError(f"{name} = {_short.repr(value)}: must be a str or None, not "
                        f"{type(value).__name__}")
    return value
