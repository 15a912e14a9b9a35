"""A small study and its figures

Every stage, the figures and the report, in well under a minute.

``g2tom run`` on the Greenwood-Tripp scenario ``paper_gt``, shrunk by ``--set`` overrides to a
3 x 3 grid of oxide fractions and lengths, six load steps and a fixed ensemble of eight oxide
patterns per cell (the full study uses adaptive ensembles on a 6 x 6 grid). ``g2tom plan`` prints
the expected time and memory first. The report's first screen follows, and Fig. 8 (resistance
against force with its band and power-law fit).
"""

import shutil
from contextlib import redirect_stderr
from io import StringIO
from pathlib import Path

from g2tom.cli.main import main

study = ["--config", "paper_gt",
         "--set", "oxide.xi=[0.3,0.5,0.7]", "--set", "oxide.lambda=[2,5,9]",
         "--set", "oxide.ensemble=fixed", "--set", "oxide.n_realizations=8",
         "--set", "loading.n_delta=6", "--set", "contact.n_radial=160", "--set", "fits.n_bootstrap=50"]

print("$ g2tom plan", " ".join(study))
main(["plan", *study])

print("\n$ g2tom run", " ".join(study), "--data-dir data --workers 1 --no-bench")
log = StringIO()
with redirect_stderr(log):  # the stages' progress lines
    main(["run", *study, "--data-dir", "data", "--workers", "1", "--no-bench", "--no-progress"])
print("\n".join(line for line in log.getvalue().splitlines() if line.startswith(("contact:", "cube:", "fits:"))))

print("\n--- data/report.md, first lines ---")
report = Path("data/report.md").read_text().splitlines()
print("\n".join(report[:report.index("## Contents")]).rstrip())

shutil.copy("data/figures/fig8_resistance.png", "fig8_resistance.png")
