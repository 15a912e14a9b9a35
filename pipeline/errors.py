"""Errors the CLI turns into exit statuses (kept free of heavy imports)."""

from __future__ import annotations

import shlex
import sys

__all__ = ["StaleInputError", "WriteError", "SolveError", "install_hint"]


class StaleInputError(RuntimeError):
    """A stage input is missing or was built from a different configuration."""


class SolveError(RuntimeError):
    """A numerical solve of a stage failed (it did not converge, or left the domain it was set up for).

    The message names what failed, where, and what to try; the CLI prints it as one line, exit
    status 1, and the stage writes nothing.
    """


class WriteError(Exception):
    """An output could not be written (a full disk, no permission, a read-only file system).

    The message names the file, the reason and what was kept (the previous file, untouched);
    the CLI prints it as one line, exit status 1.
    """


def install_hint(extra: str, *packages: str) -> str:
    """The command that installs ``packages`` into the Python running g2tom, wherever it was installed.

    Parameters
    ----------
    extra
        The g2tom optional extra that lists the packages, named as an aside.
    packages
        What pip installs.

    Returns
    -------
    str
        E.g. ``/usr/bin/python3 -m pip install tamaas (g2tom's optional extra 'reference')``.
    """
    command = " ".join(shlex.quote(word) for word in (sys.executable, "-m", "pip", "install", *packages))
    return f"{command} (g2tom's optional extra '{extra}')"
