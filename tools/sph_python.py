"""What the sph tools need from Python, asked for by name (`need("numpy")`) before importing it.

A missing module is the common case of a Python other than Debian's (pyenv, conda, a venv)
first on PATH: then the tool runs itself again with Debian's /usr/bin/python3 when that one
has the module, and otherwise stops with exit 2 saying which package to install.

Also the tools' shared handling of bad input and of their tables: `fail`, `require`,
`positive_list`, `usage_unless` and `errors_as_exit_2` (exit 2 with one line; Ctrl-C and SIGTERM
end the tool by that signal), `Unreadable` and the readers of a run's outputs that raise it
(`read_json_object`, `read_csv_columns`, `reading`), `write_atomic` (a table that is always
complete on disk), and what the study tools share about a run of sph-run: `run_child` (a child
in its own session, so that a terminal's Ctrl-C reaches the tool alone, which forwards one SIGTERM;
it never outlives its tool), `sph_run` and `read_run` (a run is usable, or "failed (exit N)",
"interrupted (...)" or "unreadable: <file>: <reason>"), `scene_copy` (a scene to write elsewhere,
its relative files made absolute), `md_cell`/`md_status_row` and `exit_if_unusable`."""
import contextlib
import csv
import ctypes
import hashlib
import importlib.util
import io
import json
import os
import pathlib
import signal
import subprocess
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


class Stopped(KeyboardInterrupt):
    """SIGTERM (or SIGHUP: the terminal closed), raised where the tool is as Ctrl-C raises
    KeyboardInterrupt (errors_as_exit_2 installs the handler), so that all unwind the same way: a
    running child is ended and waited for (run_child), then the tool dies by the signal,
    `signum`."""
    def __init__(self, signum=signal.SIGTERM):
        super().__init__()
        self.signum = signum


def _raise_stopped(signum, frame):
    raise Stopped(signum)


def die_by(signum):
    """End the process by `signum` with its default action, as shells expect of a program
    stopped by a signal (a calling loop sees 128 + signum and stops too): output flushed first."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)
    os._exit(128 + signum)  # not reached: the signal's default action ends the process


def errors_as_exit_2():
    """Bad input as the project's tools report it: a file that cannot be read or written
    (OSError) or parsed (JSON or text: JSONDecodeError, UnicodeDecodeError; CSV: csv.Error, and
    `Unreadable`, which read_csv_columns and the readers of a run's outputs raise) ends the tool
    with one line, `<tool>: error: <what>`, and exit code 2, instead of a traceback. Ctrl-C
    (KeyboardInterrupt), SIGTERM and SIGHUP (raised as `Stopped`; SIGHUP only if not ignored, as
    under nohup) end it with `<tool>: interrupted` and then by that signal itself (the shell sees
    130, 143 or 129). SIGHUP is caught because a run of sph-run is in its own session (run_child)
    and would not get the terminal's hangup: the tool ends it. Other exceptions (bugs, a
    ValueError of a computation among them) keep Python's traceback and exit 1."""
    default = sys.excepthook

    def hook(kind, value, tb):
        if issubclass(kind, BrokenPipeError):  # the reader went away (`| head`): nothing to report
            sys.exit(0)
        if issubclass(kind, KeyboardInterrupt):
            signum = getattr(value, "signum", signal.SIGINT)
            print(f"{_tool()}: interrupted" + ("" if signum == signal.SIGINT else f" ({signal.Signals(signum).name})"),
                  file=sys.stderr)
            die_by(signum)
        if issubclass(kind, Unreadable):
            fail(str(value))
        if issubclass(kind, OSError):
            where = f"{value.filename}: " if getattr(value, "filename", None) else ""
            fail(f"{where}{value.strerror or value}")
        elif issubclass(kind, (json.JSONDecodeError, UnicodeDecodeError)):
            fail(f"an input file is not valid JSON or text: {value}")
        elif issubclass(kind, csv.Error):
            fail(f"an input file is not valid CSV: {value}")
        default(kind, value, tb)

    sys.excepthook = hook
    signal.signal(signal.SIGTERM, _raise_stopped)
    if signal.getsignal(signal.SIGHUP) == signal.SIG_DFL:
        signal.signal(signal.SIGHUP, _raise_stopped)


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


def fail(message):
    """Exit 2 with one line, `<tool>: error: message` (<tool>: the script's file name)."""
    print(f"{_tool()}: error: {message}", file=sys.stderr)
    sys.exit(2)


def require(condition, message):
    """fail(message) unless condition."""
    if not condition:
        fail(message)


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


def read_csv_columns(path, columns=(), min_rows=0, final_newline=True):
    """A numeric CSV with a header row ('#' lines and blank lines skipped) as {column: [float]}.
    Raises Unreadable naming the file (and the line) if it cannot be read, if a row has another
    number of cells than the header or a cell is not a number, if a column of `columns` is
    missing, if there are fewer than `min_rows` rows, or, with `final_newline` (the files sph-run
    writes, whose every line ends with one), if the last line has no newline: a file cut short
    at a cell boundary would otherwise pass for a complete one. Files people write (an
    experiment's data) are read with final_newline=False."""
    header, data = None, None
    with reading(path), open(path) as f:
        for n, line in enumerate(f, 1):
            if final_newline and not line.endswith("\n"):
                raise ValueError(f"line {n}: cut short (the file ends inside it, without a newline)")
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
    """Write `text` to `path` through a temporary file in the same folder (`.<name>.tmp<pid>`)
    and os.replace, so that a reader, a crash or a Ctrl-C at any moment finds the previous
    complete file or the new one, never a part. The tools rewrite their tables this way after
    every run. An exception removes the temporary; a SIGKILL between writing and renaming leaves
    it, so a write first removes the `.<name>.tmp*` left by earlier processes (one writer per
    table is assumed: two tools writing the same table at once would be wrong anyway)."""
    path = pathlib.Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    with contextlib.suppress(OSError):
        for name in os.listdir(path.parent):
            if name.startswith(f".{path.name}.tmp") and name != tmp.name:
                with contextlib.suppress(OSError):
                    os.unlink(path.parent / name)
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


def md_cell(text):
    """`text` as one cell of a Markdown table: `|` escaped, line breaks as spaces."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def md_status_row(label, status, columns):
    """A Markdown table row of `columns` cells for a row with no figures: its label, then its
    status (why: failed, interrupted, unreadable, skipped), then empty cells."""
    return f"| {md_cell(label)} | {md_cell(status)} |" + " |" * (columns - 2)


# ---- a run of sph-run, as the study tools start and classify it ----

def end_child(proc, grace=10.0):
    """End a running child: SIGTERM (sph-run then stops after the step in progress and saves its
    outputs, summary.json marked "interrupted"; being in its own session (run_child), it gets no
    other signal, which it would take for a second one and stop at once), SIGKILL if it is still
    there after `grace` seconds or if another signal interrupts the wait; then wait for it, so
    that it never outlives the tool."""
    if proc.poll() is not None:
        return
    try:
        proc.terminate()
        proc.wait(timeout=grace)
    except BaseException:  # TimeoutExpired, or a second Ctrl-C / SIGTERM while waiting
        proc.kill()
        proc.wait()
        if sys.exc_info()[0] is not subprocess.TimeoutExpired:
            raise


def file_sha256(path):
    """The SHA-256 of a file's bytes as they are now (hex): what the tools record of a scene file
    beside the runs they make of it, so that --reuse can tell an edited scene from the same one."""
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _term_with_parent(libc, parent):
    """The child's side of run_child, between fork and exec: ask Linux for one SIGTERM when the
    tool dies (prctl PR_SET_PDEATHSIG; it survives exec), which covers a tool killed by SIGKILL
    and a signal that lands before run_child's `try`. A tool already gone by then (its pid no
    longer the parent's) means no run: exit at once."""
    if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG)")
    if os.getppid() != parent:
        os._exit(1)


def run_child(cmd, log, echo=None):
    """Run `cmd`, its stdout and stderr into the file `log` (each line also given to `echo`,
    if any, as it comes); returns its exit code. The child runs in a session (and so a process
    group) of its own: a terminal's Ctrl-C, sent to the terminal's foreground process group,
    reaches the tool only. On any exception while it runs (Ctrl-C, SIGTERM, SIGHUP, a bug) the
    child is ended and waited for (end_child: one SIGTERM) and what it wrote meanwhile goes to
    `log` (and `echo`) before the exception goes on. If the tool dies without that (SIGKILL), the
    child gets one SIGTERM from the kernel (_term_with_parent) and saves as it would from ours."""
    preexec = None
    if sys.platform.startswith("linux"):  # prctl is Linux's; elsewhere a killed tool's run goes on
        parent, libc = os.getpid(), ctypes.CDLL(None, use_errno=True)  # loaded here, not after the fork
        preexec = lambda: _term_with_parent(libc, parent)  # noqa: E731
    with open(log, "w") as f:
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE if echo else f, stderr=subprocess.STDOUT, text=True,
                                start_new_session=True, preexec_fn=preexec)
        try:
            if echo:
                for line in proc.stdout:
                    f.write(line)
                    echo(line)
            return proc.wait()
        except BaseException:
            end_child(proc)
            if echo:
                with contextlib.suppress(Exception):  # its last words: where it stopped, what it saved
                    for line in proc.stdout.read().splitlines(keepends=True):
                        f.write(line)
                        echo(line)
            raise
        finally:
            if proc.stdout:
                proc.stdout.close()


def scene_copy(scene, scene_path):
    """A copy of the scene `scene` (its JSON, read from `scene_path`) to write into another
    folder: every relative file it names, which sph-run and the tools read relative to the scene
    file's folder (a boundary's `file`, the OBJ of a mesh; a probe's `experiment.file`), made
    absolute from scene_path's folder, so that the copy loads wherever it is written. Values that
    are not non-empty strings are left for sph-run to report."""
    copy = json.loads(json.dumps(scene))
    home = pathlib.Path(os.path.abspath(scene_path)).parent

    def absolute(holder):
        f = holder.get("file") if isinstance(holder, dict) else None
        if isinstance(f, str) and f and not os.path.isabs(f):
            holder["file"] = str(home / f)

    if isinstance(copy, dict):
        for boundary in copy.get("boundaries", []) if isinstance(copy.get("boundaries"), list) else []:
            absolute(boundary)
        for probe in copy.get("probes", []) if isinstance(copy.get("probes"), list) else []:
            if isinstance(probe, dict):
                absolute(probe.get("experiment"))
    return copy


def interrupted_status(summary):
    """"interrupted (SIGTERM at t = 0.0123 s)" for a summary.json sph-run marked "interrupted"
    (stopped by a signal before its end time), or None."""
    i = summary.get("interrupted") if isinstance(summary, dict) else None
    if i is None:
        return None
    if not isinstance(i, dict):
        return "interrupted"
    t = i.get("t")
    return f"interrupted ({i.get('by', 'a signal')}" + (f" at t = {t:.6g} s)" if isinstance(t, (int, float)) else ")")


def read_run(out_dir, rc=0, numbers=(), keys=(), then=None):
    """What a run of sph-run into `out_dir` that exited with `rc` gave: (value, None) if it is
    usable, value being its summary.json (with a number at every dotted key of `numbers`, some
    value at every key of `keys`) or then(summary) (which reads more of the outputs and may
    raise Unreadable); otherwise (None, status): "failed (exit N)" (an earlier run's summary read
    with rc 0 that sph-run marked "failed" is exit 3, "output_failed" exit 5), "interrupted
    (<signal> at t = T s)" (a summary.json marked "interrupted": sph-run stopped by SIGINT/SIGTERM,
    exit 130/143, or an earlier run's read with rc 0) or "unreadable: <file>: <reason>"."""
    out_dir = pathlib.Path(out_dir)
    if rc != 0:
        if rc in (128 + signal.SIGINT, 128 + signal.SIGTERM):
            with contextlib.suppress(Unreadable):
                status = interrupted_status(read_json_object(out_dir / "summary.json"))
                if status:
                    return None, status
        return None, f"failed (exit {rc})"
    try:
        summary = read_json_object(out_dir / "summary.json", numbers=numbers, keys=keys)
        status = interrupted_status(summary)
        if status:
            return None, status
        # An earlier run's summary read with rc 0 (--reuse): one sph-run marked failed (exit 3)
        # or saved from its reserve (exit 5) is not a usable run either.
        for key, code in (("failed", 3), ("output_failed", 5)):
            if key in summary:
                return None, f"failed (exit {code})"
        return (then(summary) if then else summary), None
    except Unreadable as e:
        return None, f"unreadable: {e}"


def sph_run(cmd, out_dir, numbers=(), keys=(), then=None, echo=None):
    """Run sph-run (`cmd`, whose --out is `out_dir`), its output into out_dir/run.log (lines
    also to `echo`), and classify it with read_run: (value, None) or (None, status). The
    child is ended and waited for if the tool is interrupted meanwhile (run_child)."""
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    rc = run_child(cmd, out_dir / "run.log", echo)
    return read_run(out_dir, rc, numbers, keys, then)


def log_tail(out_dir, lines=5):
    """The last lines of a run's run.log, indented, for a message about a run that failed."""
    with contextlib.suppress(OSError):
        text = (pathlib.Path(out_dir) / "run.log").read_text(errors="replace").strip().splitlines()
        return "\n".join("    " + line for line in text[-lines:])
    return ""


def exit_if_unusable(bad, tables, total=None, before=()):
    """The study tools' closing check, after their tables are written: exit 2 with one line
    naming every run in `bad` ("<which run>: <status>") and any other problem in `before`,
    saying that `tables` hold every other figure; return if there is none."""
    problems = list(before)
    if bad:
        problems.append(f"{len(bad)}{f' of {total}' if total else ''} run(s) not usable ({'; '.join(bad)})")
    require(not problems, "; ".join(problems) + f"; every other figure is in {tables}")
