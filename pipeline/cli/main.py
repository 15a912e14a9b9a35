"""The ``g2tom`` entry point: one BLAS thread, then the arguments, the scenario, the checks before
work, the command, and its exit status, every failure as one line: 2 for a refused argument or
configuration, 1 for a missing or stale input or an output that could not be written (a full disk,
no permission: the previous file kept), 130 after Ctrl-C, 143 after SIGTERM, 141 when the reader
of standard output has gone."""

from __future__ import annotations

import os

# One BLAS/OpenMP thread per dask worker thread: set before numpy is imported anywhere.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import signal  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Sequence  # noqa: E402

from g2tom.before_work.resources import prepare  # noqa: E402
from g2tom.before_work.surrogate_grid import check_surrogate_grid  # noqa: E402
from g2tom.cli.arguments import attach_negative_values, build_parser, default_config  # noqa: E402
from g2tom.cli.commands import compute_options  # noqa: E402
from g2tom.config import ConfigError, Scenario  # noqa: E402
from g2tom.before_work import load_scenario
from g2tom.errors import StaleInputError, WriteError  # noqa: E402

__all__ = ["main"]

#: Commands that run the surrogate stage: its limits on the oxide grid are checked before any stage.
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
            return load_scenario(args.config, _rejoin(args.overrides))
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


def _terminate(signum: int, frame: object) -> None:
    """The SIGTERM handler: :class:`Terminated`."""
    raise Terminated
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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``g2tom`` console script; returns the exit status."""
    args = build_parser().parse_args(attach_negative_values(sys.argv[1:] if argv is None else argv))
    args.config = default_config(args)
    formatwarning = warnings.formatwarning
    warnings.formatwarning = _one_line_warning
    on_term = signal.signal(signal.SIGTERM, _terminate)
    try:
        scenario = _load(args)
        if args.command in _REACH_SURROGATE:
            check_surrogate_grid(scenario)
        if getattr(args, "workers", None) is not None:
            compute_options(args)  # --workers is checked before the plan is announced
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            scenario, args.plan_notes = prepare(args.command, scenario, getattr(args, "workers", None))
        args.handler(args, scenario)
    except ConfigError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 2
    except (StaleInputError, WriteError) as exc:  # an input to rebuild, an output that could not be written
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        terminated = isinstance(exc, Terminated)
        print(f"g2tom: {'terminated' if terminated else 'interrupted'}: {_kept(args)}", file=sys.stderr)
        return TERMINATED if terminated else INTERRUPTED
    except BrokenPipeError:
        # the reader of standard output went away (`g2tom plan | head`): no traceback, and none
        # again when Python flushes the closed pipe at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return BROKEN_PIPE
    finally:
        warnings.formatwarning = formatwarning
        signal.signal(signal.SIGTERM, on_term)
    return 0


if __name__ == "__main__":
    sys.exit(main())
