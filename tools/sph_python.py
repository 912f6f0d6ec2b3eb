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
