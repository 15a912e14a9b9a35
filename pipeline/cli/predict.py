"""``g2tom predict``: queries from the command line or a CSV file, the surrogate that answers
(``--surrogate``, the run's own, or the atlas's), and the answer as CSV, JSON or, on a terminal, a short
table (warnings on stderr)."""

from __future__ import annotations

import argparse
import csv
import io
import json
import shlex
import sys
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.before_work.preflight import check_output_file
from g2tom.config import ConfigError, Scenario, read_input_text
from g2tom.cli.parsing import number_list
from g2tom.predict.answer import choose_surrogate, predict_with
from g2tom.predict.atlas import NOT_IN_ATLAS
from g2tom.predict.domain import with_measured_roughness
from g2tom.predict.queries import OUTPUT_COLUMNS, OutsideDomainError, PartlyAnsweredWarning, check_values
from g2tom.stages.surrogate_file import SurrogateTables

__all__ = ["predict_cli", "run_instead", "to_csv", "to_json", "to_table", "INPUT_ALIASES", "TABLE_COLUMNS"]


def _cli_queries(args: argparse.Namespace) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(force, xi, lambda) from --force/--xi/--lambda lists or --csv, checked."""
    options = {"--force": args.force, "--xi": args.xi, "--lambda": args.lam}
    if args.csv is not None:
        if any(v is not None for v in options.values()):
            raise ConfigError("--csv cannot be combined with --force, --xi or --lambda: give the queries one way")
        return _read_csv(Path(args.csv))
    missing = [k for k, v in options.items() if v is None]
    if missing:
        raise ConfigError(f"{', '.join(missing)} missing: give --force, --xi and --lambda (comma-separated lists) or --csv FILE")
    values = [number_list(k, v) for k, v in options.items()]
    sizes = {v.size for v in values} - {1}
    if len(sizes) > 1:
        counts = ", ".join(f"{k} {v.size}" for k, v in zip(options, values))
        raise ConfigError(f"lists of different lengths ({counts}): give one value or the same number of values for each")
    n = max(v.size for v in values)
    return tuple(np.broadcast_to(v, (n,)).copy() for v in values)  # type: ignore[return-value]


#: Input column names (lower case) read as another: the output's ``force_N`` as ``force``.
INPUT_ALIASES = {"force_n": "force"}


def _read_csv(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns force (or force_N, as predict writes it), xi, lambda of a CSV file with a header line
    (other columns ignored)."""
    text = read_input_text("--csv", path, encoding="utf-8-sig")  # Excel's "CSV UTF-8" starts with a BOM
    try:
        rows = list(csv.reader(io.StringIO(text)))
    except csv.Error as exc:
        raise ConfigError(f"--csv {str(path)!r} is not a readable CSV file ({exc})") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if len(rows) < 2:
        raise ConfigError(f"--csv {str(path)!r} needs a header line (force,xi,lambda) and at least one query")
    header = [c.strip().lower() for c in rows[0]]
    both = [f"{target} and {alias}" for alias, target in INPUT_ALIASES.items() if alias in header and target in header]
    if both:
        raise ConfigError(f"--csv {str(path)!r}: header {rows[0]!r} has both {both[0]} (the same column): keep one")
    header = [INPUT_ALIASES.get(c, c) for c in header]
    missing = [c for c in ("force", "xi", "lambda") if c not in header]
    if missing:
        raise ConfigError(f"--csv {str(path)!r}: header {rows[0]!r} lacks column(s) {', '.join(missing)} (need force, xi, lambda)")
    index = [header.index(c) for c in ("force", "xi", "lambda")]
    out = np.empty((3, len(rows) - 1))
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ConfigError(f"--csv {str(path)!r} line {line}: {len(row)} fields, the header has {len(header)}")
        for k, (name, i) in enumerate(zip(("force", "xi", "lambda"), index)):
            try:
                out[k, line - 2] = float(row[i])
            except ValueError:
                raise ConfigError(f"--csv {str(path)!r} line {line}: {name} = {row[i]!r} is not a number") from None
    return out[0], out[1], out[2]


#: The columns of the table printed on a terminal (every column: CSV or --json); outside_domain
#: only when a query is not answered.
TABLE_COLUMNS = ("force", "xi", "lambda", "resistance", "resistance_mean_lower", "resistance_mean_upper",
                 "resistance_spread_p16", "resistance_spread_p84", "outside_domain")
#: Significant digits in that table.
TABLE_DIGITS = 4


def _label(name: str) -> str:
    """A column's name in the output: with its unit appended unless dimensionless (force_N)."""
    unit = OUTPUT_COLUMNS[name][0]
    return f"{name}_{unit}" if unit != "1" else name


def _columns(ds: xr.Dataset, names: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
    """The output's columns (flat), in the order of :data:`OUTPUT_COLUMNS`: ``names`` of them, or all
    that ``ds`` holds (numbers as float, ``outside_domain`` as text)."""
    chosen = [n for n in OUTPUT_COLUMNS if n in ds and (names is None or n in names)]
    return {n: np.asarray(ds[n].values, dtype=str if ds[n].dtype.kind == "U" else float).ravel() for n in chosen}


def _cell(value: float | str, digits: int) -> str:
    """A number with ``digits`` significant digits; text as it is."""
    return value if isinstance(value, str) else f"{value:.{digits}g}"


def to_csv(ds: xr.Dataset) -> str:
    """Prediction dataset as CSV text, one query per line, columns :data:`OUTPUT_COLUMNS` that it holds."""
    columns = _columns(ds)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(_label(n) for n in columns)
    writer.writerows([_cell(v, 10) for v in row] for row in zip(*(c.tolist() for c in columns.values())))
    return out.getvalue()


def to_json(ds: xr.Dataset) -> str:
    """Prediction dataset as one JSON object: who answered, each column's unit and meaning, and one
    object per query (NaN as null, infinities as "inf")."""
    from g2tom.stages.surrogate_file import _encode

    columns = _columns(ds)
    encoded = (c.tolist() if c.dtype.kind == "U" else _encode(c) for c in columns.values())
    rows = [dict(zip(map(_label, columns), values)) for values in zip(*encoded)]
    doc = {"answered_by": ds.attrs.get("answered_by", ""), "band": ds.attrs.get("band", ""),
           "spread": ds.attrs.get("spread", ""),
           "columns": {_label(n): {"units": OUTPUT_COLUMNS[n][0], "long_name": OUTPUT_COLUMNS[n][1]} for n in columns},
           "queries": rows}
    return json.dumps(doc, indent=1) + "\n"


def to_table(ds: xr.Dataset) -> str:
    """The main columns (:data:`TABLE_COLUMNS`) as an aligned table of :data:`TABLE_DIGITS`
    significant digits, for a terminal, under it what each band is (and that the spread over
    contacts is unknown, where it is)."""
    columns = _columns(ds, TABLE_COLUMNS)
    if not any(columns.get("outside_domain", [])):
        columns.pop("outside_domain", None)
    cells = [[_label(n) for n in columns]]
    cells += [[_cell(v, TABLE_DIGITS) for v in row] for row in zip(*(c.tolist() for c in columns.values()))]
    widths = [max(len(row[k]) for row in cells) for k in range(len(columns))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(row, widths)) for row in cells]
    lines.append("resistance_mean_*: 95 % interval of the predicted mean R; resistance_spread_*: 16-84 % of R over "
                 "contacts")
    if "comment" in ds["resistance_spread_p16"].attrs:
        lines.append(ds["resistance_spread_p16"].attrs["comment"])
    return "\n".join(lines) + "\n"


def run_instead(args: argparse.Namespace, scenario: Scenario) -> str:
    """The ``g2tom run`` command that computes this surface directly, with its stages' planned time.

    The command repeats ``--config``, the ``--set`` overrides (and, for ``--roughness``, the
    measured sigma, eta and beta) and ``--data-dir``, so that this same ``g2tom predict`` then
    answers from the run's own surrogate. The time is the sum of the stages' seconds of
    :func:`g2tom.before_work.plan.estimate` (about 1 s to compute), or a pointer to ``g2tom plan``
    where the plan refuses the scene.
    """
    from g2tom.before_work.plan import estimate

    sets = [item for pair in zip(["--set"] * len(args.overrides), args.overrides) for item in pair]
    if args.roughness is not None:
        rough = scenario.roughness
        sets += [a for key in ("sigma", "eta", "beta") for a in ("--set", f"roughness.{key}={getattr(rough, key):.6g}")]
    command = shlex.join(["g2tom", "run", "--config", args.config, *sets, "--data-dir", str(args.data_dir)])
    try:
        planned = f"its stages planned at {sum(s.seconds for s in estimate(scenario)):.3g} s"
    except ConfigError:
        planned = "see `g2tom plan` with the same options for its time"
    return (f"`{command}` computes this surface directly ({planned}, plus its checks and report); this same "
            "`g2tom predict` then answers from that run's own surrogate")


def predict_cli(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom predict``: R_el, its band and the band's components as CSV (a short table on a terminal,
    JSON with ``--json``), to stdout or ``--output``; warnings and notes on stderr."""
    force, xi, lam = _cli_queries(args)
    check_values(force, xi, lam)
    if args.output is not None:
        check_output_file("--output", args.output)
    if args.roughness is not None:
        scenario = with_measured_roughness(scenario, args.roughness, args.pixel_size)
    elif args.pixel_size is not None:
        raise ConfigError("--pixel-size is only used with --roughness FILE")
    chosen = choose_surrogate(scenario, args.data_dir, args.surrogate, option="--surrogate")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        try:
            result = predict_with(chosen, scenario, force, xi, lam, model=args.model, extrapolate=args.extrapolate)
        except OutsideDomainError as exc:
            raise OutsideDomainError(f"{exc}; or {run_instead(args, scenario)}") from None
    if not isinstance(chosen, SurrogateTables):
        print(f"g2tom: note: the atlas surrogate holds no realization spread, fit interval or open-circuit share: "
              f"columns {', '.join(NOT_IN_ATLAS)} left out (resistance_spread_p16, _p84 NaN); its band is its "
              f"{'cross-validated and held-out error where the query is' if chosen.band is not None else 'held-out error'}",
              file=sys.stderr)
    for w in caught:
        print(f"g2tom: warning: {w.message}", file=sys.stderr)
        if issubclass(w.category, PartlyAnsweredWarning):
            print(f"g2tom: note: exit status 0 with NaN answers; {run_instead(args, scenario)}", file=sys.stderr)
    print(f"g2tom: answered by {result.attrs['answered_by']}", file=sys.stderr)
    if args.json:
        text = to_json(result)
    elif args.output is None and sys.stdout.isatty():
        text = to_table(result)
        print(f"g2tom: note: the main columns, {TABLE_DIGITS} significant digits; every column in full: "
              "--output FILE (CSV), --json, or pipe the output", file=sys.stderr)
    else:
        text = to_csv(result)
    if args.output is None:
        sys.stdout.write(text)
    else:
        from g2tom.store import atomic_path

        with atomic_path(args.output) as tmp:
            tmp.write_text(text)
