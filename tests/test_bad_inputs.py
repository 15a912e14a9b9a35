"""The bad-input catalog: every case exits 2 (1: an input file to rebuild) with one clear line.

Each case runs the ``g2tom`` command in a data directory holding earlier results and checks:
the exit status; that stderr is exactly one ``g2tom: error:`` line naming what was wrong
(the parameter or file, and what is allowed or the command that fixes it); no traceback;
and that nothing on disk changed (no file lost, rewritten or left behind). The catalog is
generated from the parameter table (every range of every parameter) plus hand-written cases
for files, options and cross-stage constraints. The tally is printed.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
import shutil
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

from g2tom.cli.main import main
from g2tom.config import SECTIONS, parameter_key
from g2tom.before_work import load_scenario
from g2tom.store import stage_path
from tests.conftest import SMALL_ARGS, SMALL_OVERRIDES


@dataclasses.dataclass(frozen=True)
class Case:
    """One bad input: the command, what its error line must contain, its exit status."""

    name: str
    argv: tuple[str, ...]
    expect: tuple[str, ...]
    status: int = 2
    setup: Callable[[Path], None] | None = None


def _range_cases() -> list[Case]:
    """Values just outside every bound, non-numbers, non-finite and non-integer values."""
    cases = []
    for section, cls in SECTIONS.items():
        for f in dataclasses.fields(cls):
            key = f"{section}.{parameter_key(f)}"
            meta, ann = f.metadata, str(f.type)
            is_list = ann.startswith("list")
            wrap = (lambda v: f"[{v}]") if is_list else (lambda v: v)
            if meta["choices"]:
                cases.append(Case(f"{key} not a choice", ("params", "--set", f"{key}=bogus"), (key, "one of")))
                cases.append(Case(f"{key} a number", ("params", "--set", f"{key}=3"), (key, "one of")))
                continue
            for bound, op in (("gt", "> "), ("ge", ">= "), ("lt", "< "), ("le", "<= ")):
                limit = meta[bound]
                if limit is None:
                    continue
                if bound in ("gt", "le"):
                    value = limit if bound == "gt" else limit + max(1.0, abs(limit))
                else:
                    value = limit - 1 if bound == "ge" else limit
                if "int" in ann:
                    value = int(math.floor(value)) if bound == "ge" else int(math.ceil(value))
                cases.append(Case(f"{key} {bound} {limit:g} violated", ("params", "--set", f"{key}={wrap(value)}"),
                                  (key, "out of range", op + f"{limit:g}")))
            cases.append(Case(f"{key} not a number", ("params", "--set", f"{key}={wrap('true')}"), (key, "not a number")))
            if "int" in ann:
                cases.append(Case(f"{key} not an integer", ("params", "--set", f"{key}={wrap(2.5)}"), (key, "not an integer")))
            else:
                cases.append(Case(f"{key} nan", ("params", "--set", f"{key}={wrap('nan')}"), (key, "not finite")))
                cases.append(Case(f"{key} inf", ("params", "--set", f"{key}={wrap('inf')}"), (key, "not finite")))
    return cases


def _write(name: str, data: bytes) -> Callable[[Path], None]:
    def setup(data_dir: Path) -> None:
        (data_dir.parent / name).write_bytes(data)
    return setup


def _truncate(stage: str) -> Callable[[Path], None]:
    def setup(data_dir: Path) -> None:
        path = stage_path(data_dir, stage)
        path.write_bytes(path.read_bytes()[:4000])
    return setup


def _npy(name: str, array: np.ndarray) -> Callable[[Path], None]:
    def setup(data_dir: Path) -> None:
        np.save(data_dir.parent / name, array)
    return setup


_SMALL = SMALL_ARGS
_ROUGH = ("roughness", "--pixel-size", "1e-6")
_SURFACE = np.random.default_rng(1).normal(scale=1e-6, size=(16, 16))


def _hand_cases() -> list[Case]:
    outside = "../"  # files beside the data directory, made by a case's setup
    c = [
        # --- the 19 failures of the first campaign and their neighbours
        Case("oxide.seed = 1e30", ("oxide", "--set", "oxide.seed=1e30"), ("oxide.seed", "2**63 - 1")),
        Case("fits.seed = 2**64", ("fits", "--set", "fits.seed=18446744073709551616"), ("fits.seed", "2**63 - 1")),
        Case("fits.min_force beyond every load", ("contact", *_SMALL, "--set", "fits.fit_range=force",
                                                  "--set", "fits.min_force=1e9"),
             ("fits.min_force = 1e+09", "load step", "must be <=")),
        Case("fits.min_force at run", ("run", *_SMALL, "--set", "fits.fit_range=force", "--set", "fits.min_force=1e9"),
             ("fits.min_force",)),
        Case("fits.min_force_normalized beyond every load",
             ("contact", *_SMALL, "--set", "fits.fit_range=force_normalized", "--set", "fits.min_force_normalized=1e6"),
             ("fits.min_force_normalized = 1e+06", "load step", "must be <=")),
        Case("surrogate.rank = 1000 at run", ("run", *_SMALL, "--set", "surrogate.rank=1000"),
             ("surrogate.rank = 1000", "<= 3", "oxide.xi")),
        Case("disc spot rule on grid spots", ("contact", *_SMALL, "--set", "oxide.spot_rule=disc"),
             ("oxide.spot_rule = 'disc'", "contact.model = 'discrete'")),
        Case("segment spot rule on grid spots", ("contact", *_SMALL, "--set", "oxide.spot_rule=segment"),
             ("oxide.spot_rule = 'segment'", "contact.model = 'discrete'")),
        Case("discrete spots with area weights", ("cube", *_SMALL, "--set", "contact.model=discrete", "--set",
                                                  "cube.weights=area"), ("cube.weights = 'area'", "'radius'")),
        Case("discrete spots with a resistive film", ("run", *_SMALL, "--set", "contact.model=discrete", "--set",
                                                      "oxide.film=resistive"), ("oxide.film = 'resistive'",)),
        Case("sigma 1e-9: no two cells touch", ("contact", *_SMALL, "--set", "roughness.sigma=1e-9"),
             ("roughness.sigma = 1e-09", "Holm radius")),
        Case("sigma 1e-9 at oxide stage too", ("oxide", *_SMALL, "--set", "roughness.sigma=1e-9"), ("roughness.sigma",)),
        Case("truncated contact.nc", ("cube", *_SMALL, "--no-progress"), ("contact.nc is unreadable", "g2tom contact"),
             status=1, setup=_truncate("contact")),
        Case("truncated cube.nc", ("fits", *_SMALL), ("cube.nc is unreadable", "g2tom cube"), status=1,
             setup=_truncate("cube")),
        Case("truncated surrogate.nc for predict", ("predict", "--force", "100", "--xi", "0.3", "--lambda", "5"),
             ("surrogate.nc is unreadable", "g2tom surrogate"), status=1, setup=_truncate("surrogate")),
        Case("truncated fits.nc for figures", ("figures", *_SMALL), ("fits.nc is unreadable", "g2tom fits"), status=1,
             setup=_truncate("fits")),
        Case("fits.nc of fits.seed=8 for surrogate", ("surrogate", *_SMALL, "--set", "fits.seed=9"),
             ("fits.nc was built from a different configuration", "g2tom fits"), status=1),
        Case("read-only data dir (a file)", ("contact", "--data-dir", f"{outside}a_file"), ("--data-dir", "not a directory")),
        Case("data dir under a file", ("contact", "--data-dir", f"{outside}a_file/data"), ("--data-dir", "not writable")),
        Case("scheduler refuses", ("oxide", "--scheduler", "tcp://127.0.0.1:1"), ("--scheduler", "127.0.0.1:1")),
        Case("scheduler foo:bar", ("oxide", "--scheduler", "foo:bar"), ("--scheduler 'foo:bar'", "1..65535")),
        Case("scheduler port 0", ("oxide", "--scheduler", "tcp://localhost:0"), ("--scheduler", "1..65535")),
        Case("scheduler port 70000", ("oxide", "--scheduler", "localhost:70000"), ("--scheduler", "1..65535")),
        Case("scheduler bad scheme", ("oxide", "--scheduler", "http://localhost:8786"), ("--scheduler", "scheme")),
        Case("scheduler empty host", ("oxide", "--scheduler", "tcp://:8786"), ("--scheduler", "not an address")),
        Case("report with missing inputs", ("report", *_SMALL), ("report not written", "missing"), status=1,
             setup=lambda d: stage_path(d, "surrogate").rename(d / "surrogate.nc.bak")),
        Case("report with stale inputs", ("report", *_SMALL, "--set", "surrogate.rank=1"),
             ("report not written", "surrogate.nc was built from a different configuration"), status=1),
        Case("report with old figures", ("report", *_SMALL), ("report not written", "older than", "g2tom figures"),
             status=1, setup=lambda d: os.utime(stage_path(d, "surrogate"))),
        Case("empty .npy height map", (*_ROUGH, f"{outside}empty.npy"), ("HEIGHTMAP", "2-D"), setup=_npy("empty.npy", np.array([]))),
        Case("zero-byte .npy height map", (*_ROUGH, f"{outside}zero.npy"), ("HEIGHTMAP", "empty"), setup=_write("zero.npy", b"")),
        Case("truncated .npy height map", (*_ROUGH, f"{outside}cut.npy"), ("HEIGHTMAP", "unreadable"),
             setup=_write("cut.npy", b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4), }")),
        Case("non-UTF-8 TOML", ("params", "--config", f"{outside}latin1.toml"), ("--config", "not UTF-8"),
             setup=_write("latin1.toml", "[roughness]\nsigma = 2e-5 # \u00e9\n".encode("latin-1"))),
        Case("directory as the height map", (*_ROUGH, outside), ("HEIGHTMAP", "is a directory")),
        Case("complex height map", (*_ROUGH, f"{outside}complex.npy"), ("HEIGHTMAP", "complex-valued"),
             setup=_npy("complex.npy", _SURFACE * (1 + 1j))),
        Case("--force inf", ("predict", "--force", "inf", "--xi", "0.3", "--lambda", "5"), ("force = inf",)),
        Case("space inside a list, bad value", ("params", "--set", "oxide.xi=[0.3,", "--set", "1.5]"),
             ("oxide.xi[1] = 1.5", "out of range")),
        Case("space inside a list, unsorted", ("params", "--set", "oxide.xi=[0.5,", "--set", "0.3]"),
             ("oxide.xi", "strictly increasing")),
        # --- parameters, keys and files
        Case("unknown section", ("params", "--set", "rough.sigma=1"), ("unknown parameter 'rough.sigma'",)),
        Case("typo in key", ("params", "--set", "roughness.sigam=1"), ("did you mean 'roughness.sigma'",)),
        Case("no key", ("params", "--set", "=3"), ("unknown parameter",)),
        Case("no '='", ("params", "--set", "roughness.sigma"), ("expected key=value",)),
        Case("section without key", ("params", "--set", "roughness=1"), ("unknown parameter 'roughness'",)),
        Case("empty list", ("params", "--set", "oxide.xi=[]"), ("oxide.xi", "non-empty list")),
        Case("scalar for a list", ("params", "--set", "oxide.lambda=5"), ("oxide.lambda", "non-empty list")),
        Case("duplicate list values", ("params", "--set", "oxide.lambda=[3, 3]"), ("oxide.lambda", "strictly increasing")),
        Case("list for a scalar", ("params", "--set", "roughness.sigma=[1e-5]"), ("roughness.sigma", "not a number")),
        Case("bool for a number", ("params", "--set", "loading.n_delta=true"), ("loading.n_delta", "not a number")),
        Case("delta_min above delta_max", ("params", "--set", "loading.delta_min=3"), ("loading.delta_min", "loading.delta_max")),
        Case("equal deltas with n > 1", ("params", "--set", "loading.delta_min=2"), ("loading.delta_min", "must differ")),
        Case("window beyond r_max", ("params", "--set", "contact.r_max=0.3", "--set", "contact.window=0.5"),
             ("contact.window", "radial domain")),
        Case("window truncating the contact", ("contact", "--set", "contact.window=0.01"),
             ("contact.window = 0.01", "truncates the contact", ">= 0.3465")),
        Case("unknown spot discretization", ("contact", "--set", "contact.spots=disc"),
             ("contact.spots = 'disc'", "mean_area", "expected", "asperities")),
        Case("negative lattice constant", ("contact", "--set", "cube.model=point", "--set", "cube.lattice_constant=-1"),
             ("cube.lattice_constant = -1", ">= 0")),
        Case("discrete asperities out of reach", ("contact", "--set", "roughness.sigma=1e-9"),
             ("contact.model = 'discrete'", "0.0377 asperities", "roughness.sigma = 1e-09", "paper_gt")),
        Case("lattice term with Greenwood's form", ("contact", "--config", "paper_gt", "--set", "cube.lattice_constant=3.9"),
             ("cube.lattice_constant = 3.9", "cube.model = 'point'")),
        Case("area weights with expected spots", ("contact", "--config", "paper_gt", "--set", "cube.weights=area"),
             ("cube.weights = 'area'", "contact.spots = 'expected'", "'radius'")),
        Case("linear A* with expected spots", ("contact", "--set", "contact.area_interpolation=area_fraction"),
             ("contact.area_interpolation = 'area_fraction'", "contact.spots = 'expected'", "'separation'")),
        Case("lambda beyond every mode of the window period", ("oxide", "--config", "published", "--set", "oxide.lambda=[1e4]"),
             ("oxide.lambda", "no Fourier mode")),
        Case("missing TOML", ("params", "--config", "no_such.toml"), ("--config 'no_such.toml'", "bundled scenario")),
        Case("directory as TOML", ("params", "--config", outside), ("--config", "neither a bundled scenario")),
        Case("invalid TOML", ("params", "--config", f"{outside}bad.toml"), ("--config", "not valid TOML"),
             setup=_write("bad.toml", b"[roughness\nsigma = 1")),
        Case("unknown section in TOML", ("params", "--config", f"{outside}sec.toml"), ("unknown parameter 'rougness'",),
             setup=_write("sec.toml", b"[rougness]\nsigma = 1e-5\n")),
        Case("scalar section in TOML", ("params", "--config", f"{outside}scal.toml"), ("roughness = 3", "table"),
             setup=_write("scal.toml", b"roughness = 3\n")),
        Case("bad base in TOML", ("params", "--config", f"{outside}base.toml"), ("base = 'nope'", "bundled"),
             setup=_write("base.toml", b'base = "nope"\n')),
        Case("out of range in TOML", ("params", "--config", f"{outside}rng.toml"), ("material.nu = 0.7", "< 0.5"),
             setup=_write("rng.toml", b'base = "paper"\n[material]\nnu = 0.7\n')),
        Case("--workers 0", ("cube", "--workers", "0"), ("--workers = 0", ">= 1")),
        Case("--workers -3", ("oxide", "--workers", "-3"), ("--workers = -3", ">= 1")),
        Case("bench unknown", ("bench", "--only", "contakt"), ("--only 'contakt'", "one of")),
        # --- height maps
        Case("missing height map", (*_ROUGH, f"{outside}none.npy"), ("HEIGHTMAP", "does not exist")),
        Case("1-D height map", (*_ROUGH, f"{outside}line.npy"), ("HEIGHTMAP", "2-D"), setup=_npy("line.npy", np.ones(9))),
        Case("3-D height map", (*_ROUGH, f"{outside}cube.npy"), ("HEIGHTMAP", "2-D"), setup=_npy("cube.npy", np.ones((3, 3, 3)))),
        Case("2 x 2 height map", (*_ROUGH, f"{outside}tiny.npy"), ("HEIGHTMAP", "3 x 3"), setup=_npy("tiny.npy", np.ones((2, 2)))),
        Case("infinity in height map", (*_ROUGH, f"{outside}inf.npy"), ("HEIGHTMAP", "non-finite"),
             setup=_npy("inf.npy", np.where(np.eye(16) > 0, np.inf, _SURFACE))),
        Case("too many NaN in height map", (*_ROUGH, f"{outside}nan.npy"), ("HEIGHTMAP", "37.5%", "undefined", "25%"),
             setup=_npy("nan.npy", np.where(np.isin((np.arange(16)[:, None] + np.arange(16)) % 8, (0, 3, 5)), np.nan,
                                            _SURFACE))),  # 37.5 %, single pixels: none is a frame
        Case("frame of NaN leaves too small a map", (*_ROUGH, f"{outside}frame.npy"),
             ("HEIGHTMAP", "cutoff wavelength", "out of range", "the measured area's largest disc"),
             setup=_npy("frame.npy", np.where(np.arange(16)[:, None] < 6, np.nan, _SURFACE))),
        Case("flat height map", (*_ROUGH, f"{outside}flat.npy"), ("HEIGHTMAP", "flat"),
             setup=_npy("flat.npy", np.add.outer(np.arange(8.0), np.arange(8.0)))),
        Case("string height map", (*_ROUGH, f"{outside}str.npy"), ("HEIGHTMAP", "real numbers"),
             setup=_npy("str.npy", np.array([["a"] * 4] * 4))),
        Case("garbage text height map", (*_ROUGH, f"{outside}map.txt"), ("HEIGHTMAP", "unreadable"),
             setup=_write("map.txt", b"1 2 x\n3 4 5\n")),
        Case("ragged text height map", (*_ROUGH, f"{outside}rag.txt"), ("HEIGHTMAP", "unreadable"),
             setup=_write("rag.txt", b"1 2 3\n3 4\n1 1 1\n")),
        Case("blank text height map", (*_ROUGH, f"{outside}blank.txt"), ("HEIGHTMAP",), setup=_write("blank.txt", b"\n\n")),
        Case("binary as text height map", (*_ROUGH, f"{outside}bin.dat"), ("HEIGHTMAP", "unreadable"),
             setup=_write("bin.dat", b"\xff\xfe\x00\x01" * 10)),
        Case("truncated netCDF height map", (*_ROUGH, f"{outside}map.nc"), ("HEIGHTMAP", "unreadable"),
             setup=_write("map.nc", b"\x89HDF\r\n\x1a\n" + b"\x00" * 40)),
        Case("pickled object .npy", (*_ROUGH, f"{outside}obj.npy"), ("HEIGHTMAP", "unreadable"),
             setup=_npy("obj.npy", np.array([object()] * 9, dtype=object).reshape(3, 3))),
    ]
    c += [
        Case("unknown option", ("contact", "--bogus"), ("unrecognized arguments: --bogus",)),
        Case("--workers not a number", ("oxide", "--workers", "two"), ("--workers", "invalid int value")),
        Case("missing --pixel-size for a .npy", ("roughness", f"{outside}nopix.npy"), ("no pixel size", "--pixel-size"),
             setup=_npy("nopix.npy", _SURFACE)),
        Case("--force not a number", ("predict", "--force", "lots", "--xi", "0.3", "--lambda", "5"), ("--force",)),
        Case("unknown command", ("bogus",), ("invalid choice: 'bogus'",)),
    ]
    for value in ("0", "-1e-6", "inf", "nan"):
        c.append(Case(f"--pixel-size {value}", ("roughness", "--pixel-size", value, f"{outside}none.npy"),
                      ("--pixel-size", "> 0")))
    # extreme values: a refusal naming the input, in plain numbers, never an overflow
    surface = ("surface", f"{outside}rough.npy", "--pixel-size", "5e-7", "--force", "0.01", "--set", "indenter.radius=1e-3")
    rough = _npy("rough.npy", np.random.default_rng(1).normal(size=(256, 256)) * 2e-7)
    c += [
        Case("plan with a sphere of 1e300 m", ("plan", "--set", "indenter.radius=1e300"),
             ("indenter.radius = 1e+300", "<= about", "1.68e+153 x 1.68e+153 cells")),
        Case("plan with a cone of 1e-300 rad", ("plan", "--set", "indenter.shape=cone", "--set", "indenter.cone_angle=1e-300"),
             ("indenter.cone_angle = 1e-300", ">= about")),
        Case("plan with eta 1e300", ("plan", "--set", "roughness.eta=1e300"), ("roughness.eta = 1e+300", "1.28e+148 x 1.28e+148 cells", "<= about")),
        Case("surface --at nan,nan", (*surface, "--at", "nan,nan"), ("--at = nan,nan", "finite"), setup=rough),
        Case("surface --correlation-length 1e300", (*surface, "--xi", "0.3", "--correlation-length", "1e300"),
             ("--correlation-length = 1e+300", "[5e-07, 0.128]"), setup=rough),
        Case("surface --pixel-size 1e-300", ("surface", f"{outside}rough.npy", "--pixel-size", "1e-300", "--force", "0.01"),
             ("--pixel-size = 1e-300", "[1e-12, 1]"), setup=rough),
        Case("predict --surrogate naming a file that is not one",
             ("predict", "--force", "100", "--xi", "0.3", "--lambda", "5", "--surrogate", f"{outside}not_a_surrogate.nc"),
             ("--surrogate", "not_a_surrogate.nc", "not a readable netCDF file"), setup=_write("not_a_surrogate.nc", b"x" * 64)),
        Case("surface on an unreachable scheduler", (*surface, "--scheduler", "tcp://127.0.0.1:1"),
             ("--scheduler 'tcp://127.0.0.1:1'", "no dask scheduler"), setup=rough),
    ]
    for flag, value in (("--force", "-5"), ("--force", "nan"), ("--force", "0"), ("--xi", "0"), ("--xi", "1"),
                        ("--xi", "1.5"), ("--xi", "nan"), ("--lambda", "0"), ("--lambda", "-2"), ("--lambda", "inf")):
        args = {"--force": "100", "--xi": "0.3", "--lambda": "5", flag: value}
        c.append(Case(f"predict {flag} {value}", ("predict", *[a for kv in args.items() for a in kv]),
                      (f"{flag.lstrip('-')} = ",)))
    return c


CASES = _range_cases() + _hand_cases()


def _snapshot(root: Path) -> dict[str, tuple[int, str]]:
    """Every file under ``root``: modification time and content hash."""
    return {
        str(p.relative_to(root)): (p.stat().st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
        for p in sorted(root.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def results(tmp_path_factory, small_stages) -> Path:
    """A data directory with every stage file, figure and the report of the small run (conftest's
    ``small_stages``, copied), and a file beside it."""
    data = tmp_path_factory.mktemp("results") / "data"
    shutil.copytree(small_stages, data)
    (data.parent / "a_file").write_text("not a directory")
    return data


def _run(case: Case, root: Path, capsys, pristine: dict[str, Any]) -> str | None:
    """Run one case in a copy of ``root``; None if handled, else what went wrong.

    The copy is made again only where the previous case left it other than a fresh copy (a case with
    a ``setup``, or one that changed files): ``pristine`` holds a fresh copy's snapshot (``"files"``)
    and whether the copy now differs from it (``"dirty"``). Every case's files are still compared,
    whole, before and after it runs."""
    work = root.parent / "case"
    data = work / root.name
    if pristine.get("dirty", True) or "files" not in pristine:
        if work.exists():
            shutil.rmtree(work)
        shutil.copytree(root.parent, work, symlinks=True)  # copy2: the copies keep the originals' times
        pristine.setdefault("files", _snapshot(work))
    if case.setup:
        case.setup(data)
    before = _snapshot(work) if case.setup else pristine["files"]
    pristine["dirty"] = True  # until the files are found as they were
    capsys.readouterr()
    argv = list(case.argv)
    if "--data-dir" not in argv:
        argv[1:1] = ["--data-dir", str(data)]
    argv = [a.replace("../", f"{work}/") if a.startswith("../") else a for a in argv]
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse refusals
        status = exc.code
    except BaseException as exc:  # noqa: BLE001 - a traceback is exactly what the catalog hunts
        return f"raised {type(exc).__name__}: {exc}"
    out = capsys.readouterr()
    lines = [line for line in out.err.splitlines() if line.strip()]
    if status != case.status:
        return f"exit status {status}, expected {case.status}: {out.err.strip()[:300]}"
    if len(lines) != 1 or not lines[0].startswith("g2tom: error: "):
        return f"stderr is not one error line: {out.err[:300]!r}"
    missing = [e for e in case.expect if e not in lines[0]]
    if missing:
        return f"message lacks {missing}: {lines[0]}"
    if "Traceback" in out.err + out.out:
        return "printed a traceback"
    after = _snapshot(work)
    if after != before:
        return "files on disk changed"
    pristine["dirty"] = after != pristine["files"]
    return None


def test_bad_input_catalog(results: Path, capsys) -> None:
    assert len(CASES) >= 150, len(CASES)
    assert len({c.name for c in CASES}) == len(CASES), "case names must be unique"
    pristine: dict[str, Any] = {}
    failures = {c.name: why for c in CASES if (why := _run(c, results, capsys, pristine))}
    handled = len(CASES) - len(failures)
    with capsys.disabled():
        print(f"\nbad-input catalog: {len(CASES)} cases tried, {handled} handled")
    assert not failures, "\n".join(f"{name}: {why}" for name, why in failures.items())


def test_catalog_scenarios_are_otherwise_valid() -> None:
    """The parameter table cases each break exactly one parameter of a valid scenario."""
    load_scenario("paper_gt", SMALL_OVERRIDES)
    assert sum(c.argv[0] == "params" for c in CASES) > 100


def test_a_reader_that_closes_the_pipe_early_gets_no_traceback() -> None:
    """`g2tom plan | head -1`: the reader goes away while g2tom writes (here: before it writes
    at all, so the test does not depend on the pipe's buffer); g2tom stops quietly with the shell's
    status for SIGPIPE (141), no traceback and no "Exception ignored" on standard error."""
    import subprocess
    import sys

    g2tom = [sys.executable, "-c", "import sys; from g2tom.cli.main import main; sys.exit(main())"]
    proc = subprocess.Popen([*g2tom, "plan"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # the reader is gone before the first write
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert "Traceback" not in err and "BrokenPipeError" not in err and "Exception ignored" not in err, err


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (a device that is always full)")
def test_standard_output_on_a_full_disk_is_one_line() -> None:
    """`g2tom params > file` on a full disk: one line naming standard output and why, status 1."""
    import subprocess
    import sys

    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "g2tom.cli.main", "params"], stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr == "g2tom: error: cannot write standard output: No space left on device\n", proc.stderr
