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

    def hook(kind, value, tb):
        if issubclass(kind, BrokenPipeError):  # the reader went away (`| head`): nothing to report
            sys.exit(0)
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
        tool = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "tool"
        print(f"{tool}: error: {message}", file=sys.stderr)
        sys.exit(2)


def usage_unless(arguments, doc):
    """A script taking `arguments` positional arguments: with -h/--help prints `doc` and exits 0;
    with another count prints it to stderr and exits 2."""
    if len(sys.argv) == arguments + 1 and sys.argv[1] not in ("-h", "--help"):
        return
    wanted = len(sys.argv) == 2 and sys.argv[1] in ("-h", "--help")
    print(doc.strip(), file=sys.stdout if wanted else sys.stderr)
    sys.exit(0 if wanted else 2)
