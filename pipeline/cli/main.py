"""The ``g2tom`` entry point: one BLAS thread, then the arguments, the scenario, the checks before
work, the command, and its exit status, every failure as one line: 2 for a refused argument or
configuration, 1 for a missing or stale input or an output that could not be written (a full disk,
no permission: the previous file kept), 130 after Ctrl-C, 143 after SIGTERM, 141 when the reader
of standard output has gone."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Mapping, Sequence


def numba_cache_dir(environ: Mapping[str, str], package: Path) -> str | None:
    """Where numba should keep the compiled code of g2tom's ``cache=True`` functions, or None to leave
    numba's own choice.

    numba caches beside each source (``__pycache__``), else under the user's cache folder; on a
    read-only installation with an unwritable HOME (a container's read-only root) it has neither and
    refuses to import the module. None when the user has set ``NUMBA_CACHE_DIR`` or the package's
    folder is writable; otherwise the first folder that can be made and written of
    ``$XDG_CACHE_HOME/g2tom/numba``, ``$HOME/.cache/g2tom/numba`` and ``<temp>/g2tom-numba-<uid>``.

    Parameters
    ----------
    environ
        The environment (``os.environ``).
    package
        The folder of the sources with cached functions (``g2tom/physics``).
    """
    if "NUMBA_CACHE_DIR" in environ:
        return None
    beside = package / "__pycache__" if (package / "__pycache__").exists() else package
    if beside.is_dir() and os.access(beside, os.W_OK):
        return None
    candidates = [Path(environ[v]) / (".cache" if v == "HOME" else "") / "g2tom" / "numba"
                  for v in ("XDG_CACHE_HOME", "HOME") if environ.get(v)]
    candidates.append(Path(tempfile.gettempdir()) / f"g2tom-numba-{os.getuid()}")
    for folder in candidates:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(folder, os.W_OK):
            return str(folder)
    return None


def numba_threads_problem(environ: Mapping[str, str]) -> str | None:
    """Why numba would fail on ``NUMBA_NUM_THREADS`` (with a traceback, on import) or ignore it; None if it
    is unset or allowed."""
    text = environ.get("NUMBA_NUM_THREADS")
    if text is None or (text.strip().isdigit() and int(text) >= 1):
        return None
    return (f"NUMBA_NUM_THREADS = {text!r} is not allowed: must be a whole number >= 1 (this machine has "
            f"{os.cpu_count() or 1} cores); unset it for one numba thread per core")


# One BLAS/OpenMP thread per dask worker thread, and numba's cache where it can be written: set before
# numpy and numba are imported anywhere (workers inherit them). A NUMBA_NUM_THREADS numba would fail on
# is set aside so that the imports below succeed; main refuses it as one line.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
_numba_cache = numba_cache_dir(os.environ, Path(__file__).resolve().parent.parent / "physics")
if _numba_cache:
    os.environ["NUMBA_CACHE_DIR"] = _numba_cache
_NUMBA_THREADS = numba_threads_problem(os.environ)
if _NUMBA_THREADS:
    del os.environ["NUMBA_NUM_THREADS"]

import argparse  # noqa: E402
import signal  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402

from g2tom.before_work.resources import prepare  # noqa: E402
from g2tom.before_work.surrogate_grid import check_surrogate_grid  # noqa: E402
from g2tom.cli.arguments import attach_negative_values, build_parser, default_config  # noqa: E402
from g2tom.cli.commands import compute_options  # noqa: E402
from g2tom.config import ConfigError, Scenario  # noqa: E402
from g2tom.before_work import load_scenario  # noqa: E402
from g2tom.errors import SolveError, StaleInputError, WriteError  # noqa: E402

__all__ = ["main"]

#: Commands that run the surrogate stage: its limits on the oxide grid are checked before any stage (and a
#: grid too small for the joint surrogate is said, with the plan).
_REACH_SURROGATE = ("run", "surrogate")


def _rejoin(overrides: Sequence[str]) -> list[str]:
    """Glue back ``--set`` values that were split at spaces inside brackets or quotes.

    make's ``SET="oxide.xi=[0.3, 0.5]"`` becomes ``--set oxide.xi=[0.3,`` ``--set 0.5]``: a
    fragment is joined to the next until its brackets balance and its quotes close.
    """
    out: list[str] = []
    pending = ""
    for item in overrides:
        pending = f"{pending} {item}" if pending else item
        text = pending.partition("=")[2]
        balanced = (text.count("[") <= text.count("]") and text.count('"') % 2 == 0
                    and text.count("'") % 2 == 0)
        if balanced:
            out.append(pending)
            pending = ""
    if pending:
        out.append(pending)
    return out


def _load(args: argparse.Namespace) -> Scenario:
    """The scenario of ``--config`` and ``--set``; unreadable files become ConfigError."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            # a measured map (`g2tom surface`) replaces the scenario's roughness
            return load_scenario(args.config, _rejoin(args.overrides), rough_scene=args.command != "surface")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"--config {args.config!r} is not UTF-8 text (byte {exc.start}: "
                          f"{exc.object[exc.start:exc.start + 1]!r}); save it as UTF-8") from None
    except OSError as exc:
        raise ConfigError(f"--config {args.config!r} is unreadable ({exc.strerror or exc})") from None


def _one_line_warning(message, category, filename, lineno, line=None) -> str:  # noqa: ANN001
    """Warnings as one ``g2tom: warning:`` line, without the source line that raised them."""
    return f"g2tom: warning: {message}\n"


#: Exit status after Ctrl-C (128 + SIGINT, as a shell reports a command killed by it).
INTERRUPTED = 130
#: Exit status after SIGTERM (128 + SIGTERM), reported as Ctrl-C is.
TERMINATED = 143


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the main thread is, to unwind (and clean up) as Ctrl-C does."""


def _ignore_further_signals() -> None:
    """Ignore Ctrl-C and SIGTERM from now on: the first one unwinds the command, and a second (Ctrl-C
    pressed twice; ``timeout``, which signals the command and then its whole process group) would
    otherwise break into that unwinding with a traceback. :func:`main` restores the handlers when
    called from Python."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)


def _terminate(signum: int, frame: object) -> None:
    """The SIGTERM handler: :class:`Terminated`, the signals ignored while it unwinds."""
    _ignore_further_signals()
    raise Terminated


def _interrupt(signum: int, frame: object) -> None:
    """The SIGINT handler: KeyboardInterrupt, as Python's own, the signals ignored while it unwinds."""
    _ignore_further_signals()
    raise KeyboardInterrupt
#: Exit status when standard output's reader has gone (128 + SIGPIPE, as a shell reports it).
BROKEN_PIPE = 141


def _kept(args: argparse.Namespace) -> str:
    """What an interrupted command kept, and how to go on from it (one line)."""
    if args.command == "validate":
        from g2tom.reference.validate import output_folder

        where = output_folder(args.data_dir, args.surface) / "cases"
        return (f"the cases finished so far are kept in {where}; run the same `g2tom validate` command again to "
                "continue from them")
    if args.command == "atlas":
        return (f"the scenes finished so far are kept in {Path(args.data_dir) / 'atlas'}; run the same `g2tom atlas` "
                "command again to continue from them")
    return "stopped before the end; run the command again"


def _interruption_in(exc: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM (:class:`Terminated`) that caused ``exc``, through its chain of causes, or None."""
    seen: set[int] = set()
    link: BaseException | None = exc
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return link
        seen.add(id(link))
        link = link.__cause__ or link.__context__
    return None


def _stopped(args: argparse.Namespace, signal_exc: KeyboardInterrupt) -> int:
    """One line for Ctrl-C or SIGTERM, saying what was kept; the exit status a shell reports for it."""
    terminated = isinstance(signal_exc, Terminated)
    print(f"g2tom: {'terminated' if terminated else 'interrupted'}: {_kept(args)}", file=sys.stderr)
    return TERMINATED if terminated else INTERRUPTED


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``g2tom`` console script; returns the exit status."""
    words = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(attach_negative_values(words))
    args.command_line = ["g2tom", *words]  # what reproduces this run, for the outputs that say so
    args.config = default_config(args)
    formatwarning = warnings.formatwarning
    warnings.formatwarning = _one_line_warning
    on_term = signal.signal(signal.SIGTERM, _terminate)
    on_int = signal.signal(signal.SIGINT, _interrupt)
    try:
        if _NUMBA_THREADS:
            raise ConfigError(_NUMBA_THREADS)
        scenario = _load(args)
        grid_note = check_surrogate_grid(scenario) if args.command in _REACH_SURROGATE else None
        if getattr(args, "workers", None) is not None:
            compute_options(args)  # --workers is checked before the plan is announced
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            scenario, args.plan_notes = prepare(args.command, scenario, getattr(args, "workers", None))
        if grid_note:  # said with the plan, once every check has passed
            args.plan_notes = [*args.plan_notes, f"g2tom: note: {grid_note}"]
        args.handler(args, scenario)
    except ConfigError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 2
    except (StaleInputError, SolveError, WriteError) as exc:  # an input to rebuild, a solve that failed, an
        # output that could not be written
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        return _stopped(args, exc)
    except SystemError as exc:
        # a signal that came while a compiled extension called back into Python (numba loading a
        # cached function, say) arrives wrapped: the extension reports "a result with an exception set"
        cause = _interruption_in(exc)
        if cause is None:
            raise
        return _stopped(args, cause)
    except BrokenPipeError:
        # the reader of standard output went away (`g2tom plan | head`): no traceback, and none
        # again when Python flushes the closed pipe at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return BROKEN_PIPE
    except OSError as exc:
        # a write the command's own checks did not name: standard output on a full or read-only disk
        # (`g2tom params > /full/disk/file`) carries no file name
        where = exc.filename if exc.filename is not None else "standard output"
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # nothing more to flush at exit
        print(f"g2tom: error: cannot write {where}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    finally:
        warnings.formatwarning = formatwarning
        # As the command (argv None) the process exits next, joining the threads still finishing their
        # tasks: after a signal, the signals stay ignored through that. Called from Python, restored.
        if argv is not None or signal.getsignal(signal.SIGTERM) is not signal.SIG_IGN:
            signal.signal(signal.SIGTERM, on_term)
            signal.signal(signal.SIGINT, on_int)
    return 0


if __name__ == "__main__":
    sys.exit(main())
