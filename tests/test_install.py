"""The distribution installs one package, ``g2tom``: its wheel holds nothing named ``pipeline`` or
``analysis`` at the top level, and the source tree's folders map onto ``g2tom`` and ``g2tom.analysis``."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> zipfile.ZipFile:
    out = tmp_path_factory.mktemp("wheel")
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(out), str(ROOT)], capture_output=True, text=True)
    if built.returncode != 0:
        pytest.skip(f"no wheel could be built here: {built.stderr.strip().splitlines()[-1:]}")
    return zipfile.ZipFile(next(out.glob("g2tom-*.whl")))


def test_the_wheel_installs_one_top_level_package(wheel) -> None:
    tops = {name.split("/")[0] for name in wheel.namelist()}
    assert {t for t in tops if not t.endswith(".dist-info")} == {"g2tom"}


def test_every_source_module_and_data_file_is_in_the_wheel(wheel) -> None:
    names = set(wheel.namelist())
    expected = {"g2tom/" + p.relative_to(ROOT / "pipeline").as_posix() for p in (ROOT / "pipeline").rglob("*.py")}
    expected |= {"g2tom/analysis/" + p.relative_to(ROOT / "analysis").as_posix() for p in (ROOT / "analysis").rglob("*.py")}
    expected |= {"g2tom/scenarios/" + p.name for p in (ROOT / "pipeline" / "scenarios").glob("*.toml")}
    expected.add("g2tom/variables.toml")
    if (ROOT / "pipeline" / "atlas_surrogate.json").exists():
        expected.add("g2tom/atlas_surrogate.json")
    assert not expected - names, sorted(expected - names)
    assert "g2tom/cli/main.py" in names and "g2tom/analysis/report.py" in names
