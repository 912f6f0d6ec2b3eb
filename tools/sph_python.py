"""What the sph tools need from Python, asked for by name (`need("numpy")`) before importing it.

A missing module is the common case of a Python other than Debian's (pyenv, conda, a venv)
first on PATH: then the tool runs itself again with Debian's /usr/bin/python3 when that one
has the module, and otherwise stops with exit 2 saying which package to install."""
import importlib.util
import os
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
    `<tool>: error: <what>`, and exit code 2, instead of a traceback. Other exceptions (bugs)
    keep Python's traceback and exit 1."""
    import json

    default = sys.excepthook
    tool = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "tool"

    def hook(kind, value, tb):
        if issubclass(kind, OSError):
            where = f"{value.filename}: " if getattr(value, "filename", None) else ""
            print(f"{tool}: error: {where}{value.strerror or value}", file=sys.stderr)
        elif issubclass(kind, (json.JSONDecodeError, UnicodeDecodeError)):
            print(f"{tool}: error: an input file is not valid JSON or text: {value}", file=sys.stderr)
        else:
            default(kind, value, tb)
            return
        sys.exit(2)

    sys.excepthook = hook


def positive_list(text, option, allow_zero=False):
    """A comma-separated list of numbers, each > 0 (or >= 0), for `option`; exit 2 naming it
    otherwise."""
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = None
    if not values or any(not (v >= 0 if allow_zero else v > 0) for v in values):
        tool = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "tool"
        bound = ">= 0" if allow_zero else "> 0"
        print(f"{tool}: error: {option} {text!r}: expected comma-separated numbers {bound}", file=sys.stderr)
        sys.exit(2)
    return values


def require(condition, message):
    """Exit 2 with `<tool>: error: message` unless condition."""
    if not condition:
        tool = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "tool"
        print(f"{tool}: error: {message}", file=sys.stderr)
        sys.exit(2)
