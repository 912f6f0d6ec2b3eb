"""What the sph tools need from Python, asked for by name (`need("numpy")`) before importing it.

A missing module is the common case of a Python other than Debian's (pyenv, conda, a venv)
first on PATH: then the tool runs itself again with Debian's /usr/bin/python3 when that one
has the module, and otherwise stops with exit 2 saying which package to install.

Also the tools' shared handling of bad input and of their tables: `require`, `positive_list`,
`usage_unless` and `errors_as_exit_2` (exit 2 with one line), `Unreadable` and the readers of a
run's outputs that raise it (`read_json_object`, `read_csv_columns`, `reading`), and
`write_atomic` (a table that is always complete on disk)."""
import contextlib
import csv
import importlib.util
import io
import json
import os
import pathlib
import sys

_DEBIAN = "/usr/bin/python3"
_PACKAGES = {"numpy": "python3-numpy", "matplotlib": "python3-matplotlib"}


def need(*modules):
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if not missing:
        return
    here = os.path.realpath(sys.executable or "")
    if os.path.exists(_DEBIAN) and here != os.path.realpath(_DEBIAN) and not os.environ.get("SPH_PYTHON_REEXEC"):
        os.environ["SPH_PYTHON_REEXEC"] = "1"  # once: never loop between interpreters
        os.execv(_DEBIAN, [_DEBIAN] + sys.argv)
    tool = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "this tool"
    pkgs = " ".join(_PACKAGES.get(m, "python3-" + m) for m in missing)
    other = "" if here == os.path.realpath(_DEBIAN) else f" or run it with {_DEBIAN}"
    print(f"{tool}: needs {', '.join(missing)}, which {sys.executable} does not have: "
          f"install it (Debian: apt-get install {pkgs}; tools/install_deps.sh does){other}", file=sys.stderr)
    sys.exit(2)


def errors_as_exit_2():
    """Bad input as the project's tools report it: a file that cannot be read or written
    (OSError) or parsed (JSON, CSV: ValueError from the parsers) ends the tool with one line,
    `<tool>: error: <what>`, and exit code 2, instead of a traceback; so does an `Unreadable`
    output of a run. Ctrl-C (KeyboardInterrupt) ends it with `<tool>: interrupted` and exit 130,
    as shells expect. Other exceptions (bugs) keep Python's traceback and exit 1."""
    default = sys.excepthook

    def hook(kind, value, tb):
        if issubclass(kind, BrokenPipeError):  # the reader went away (`| head`): nothing to report
            sys.exit(0)
        if issubclass(kind, KeyboardInterrupt):
            print(f"{_tool()}: interrupted", file=sys.stderr)
            sys.exit(130)
        if issubclass(kind, Unreadable):
            require(False, str(value))
        if issubclass(kind, OSError):
            where = f"{value.filename}: " if getattr(value, "filename", None) else ""
            require(False, f"{where}{value.strerror or value}")
        elif issubclass(kind, (json.JSONDecodeError, UnicodeDecodeError)):
            require(False, f"an input file is not valid JSON or text: {value}")
        default(kind, value, tb)

    sys.excepthook = hook


def positive_list(text, option, allow_zero=False):
    """A comma-separated list of numbers, each > 0 (or >= 0), for `option`; exit 2 naming it
    otherwise."""
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = None
    require(values and all(v >= 0 if allow_zero else v > 0 for v in values),
            f"{option} {text!r}: expected comma-separated numbers {'>= 0' if allow_zero else '> 0'}")
    return values


def require(condition, message):
    """Exit 2 with `<tool>: error: message` unless condition."""
    if not condition:
        print(f"{_tool()}: error: {message}", file=sys.stderr)
        sys.exit(2)


def _tool():
    return os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "tool"


def usage_unless(arguments, doc):
    """A script taking `arguments` positional arguments: with -h/--help prints `doc` and exits 0;
    with another count prints it to stderr and exits 2."""
    if len(sys.argv) == arguments + 1 and sys.argv[1] not in ("-h", "--help"):
        return
    wanted = len(sys.argv) == 2 and sys.argv[1] in ("-h", "--help")
    print(doc.strip(), file=sys.stdout if wanted else sys.stderr)
    sys.exit(0 if wanted else 2)


class Unreadable(ValueError):
    """A file a run wrote that is missing, truncated or not in the form expected. str() names the
    file and what was wrong, for a table's status cell: `unreadable: <file>: <reason>`."""


@contextlib.contextmanager
def reading(path):
    """Inside the block an OSError (missing, unreadable) or ValueError (not parsable) is raised
    again as Unreadable naming `path`. Keep the block to the reading: a ValueError of a
    computation would be reported as the file's."""
    try:
        yield
    except Unreadable:
        raise
    except OSError as e:
        raise Unreadable(f"{path}: {e.strerror or e}") from None
    except ValueError as e:  # json.JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise Unreadable(f"{path}: {e}") from None


def read_json_object(path, numbers=(), keys=()):
    """The JSON object in `path` (a run's summary.json), with a number at every dotted key in
    `numbers` ("physics.particle_radius") and some value at every key in `keys`; Unreadable
    naming the file and the key otherwise."""
    with reading(path):
        try:
            data = json.loads(pathlib.Path(path).read_text())
        except json.JSONDecodeError as e:
            raise ValueError(f"not valid JSON ({e})") from None
    if not isinstance(data, dict):
        raise Unreadable(f"{path}: expected a JSON object, found {type(data).__name__}")
    absent = object()
    for dotted in list(numbers) + list(keys):
        value = data
        for part in dotted.split("."):
            value = value.get(part, absent) if isinstance(value, dict) else absent
        if value is absent:
            raise Unreadable(f'{path}: no "{dotted}"')
        if dotted in numbers and (isinstance(value, bool) or not isinstance(value, (int, float))):
            raise Unreadable(f'{path}: "{dotted}": expected a number, found {json.dumps(value)[:40]}')
    return data


def read_csv_columns(path, columns=(), min_rows=0):
    """A numeric CSV with a header row ('#' lines and blank lines skipped) as {column: [float]}.
    Raises OSError if it cannot be read, and ValueError naming the line if a row has another
    number of cells than the header (a truncated file), a cell is not a number, a column of
    `columns` is missing or there are fewer than `min_rows` rows."""
    header, data = None, None
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip() or line.startswith("#"):
                continue
            cells = line.strip().split(",")
            if header is None:
                header, data = cells, [[] for _ in cells]
                continue
            if len(cells) != len(header):
                raise ValueError(f"line {n}: {len(cells)} values, expected {len(header)} as in the header")
            for column, cell in zip(data, cells):
                try:
                    column.append(float(cell))
                except ValueError:
                    raise ValueError(f"line {n}: {cell!r} is not a number") from None
    if header is None:
        raise ValueError("empty: expected a header row")
    missing = [c for c in columns if c not in header]
    if missing:
        raise ValueError(f"no column {', '.join(missing)} (header: {','.join(header)})")
    rows = len(data[0]) if data else 0
    if rows < min_rows:
        raise ValueError(f"{rows} rows, expected at least {min_rows}")
    return dict(zip(header, data))


def write_atomic(path, text):
    """Write `text` to `path` through a temporary file in the same folder and os.replace, so that
    a reader, a crash or a Ctrl-C at any moment finds the previous complete file or the new one,
    never a part. The tools rewrite their tables this way after every run."""
    path = pathlib.Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        with open(tmp, "w", newline="") as f:  # newline="": csv's \r\n row ends kept as written
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def csv_text(rows, columns):
    """rows (dicts) as CSV text with the header `columns`; a key a row lacks is an empty cell."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns)
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()
