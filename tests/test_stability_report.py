"""The report's certified-region lines (fuzzkit.report.certified)."""

from __future__ import annotations

import re

import pytest

from fuzzkit.report.certified import latency_lines, stiffness_lines
from fuzzkit.studies.experiments import DEFAULT_GAINS
from fuzzkit.studies.latency_sweep import StabilityMap

pytestmark = pytest.mark.slow


def test_stiffness_lines_overlay_the_certificate_and_the_impact_speed():
    study = {
        ("pi", "default"): [
            (10.0, {"tripped": 0.0, "settling_time_s": 0.1}),
            (1000.0, {"tripped": 1.0, "settling_time_s": None}),
        ]
    }
    md = "\n".join(stiffness_lines(study, {("pi", "default"): DEFAULT_GAINS["pi"]}, "x"))
    assert "| 10 | C, settled |" in md
    assert "| 1000 | -, tripped |" in md
    delay_ms = float(re.search(r"stiffness x speed x (\d+) ms", md).group(1))
    speeds = [float(v) for v in re.findall(r"\| ([\d.]+) mm/s \|", md)]
    # (limit - set point) / (stiffness x delay): 15 N / (10 N/mm x delay), 100x less at 1000
    assert speeds[0] == pytest.approx(15.0 / (10.0 * delay_ms * 1e-3), rel=0.02)
    assert speeds[0] / speeds[1] == pytest.approx(100.0, rel=0.02)


def test_latency_lines_put_the_certified_delay_beside_the_simulated_one():
    maps = [StabilityMap("pi", (1.0, 8.0), (0, 1, 2), ((True, True, True), (True, False, False)))]
    md = "\n".join(latency_lines(maps, "macvicar_whelan"))
    assert "| 1 | 2 / 2 |" in md  # the defaults: every delay certified, as simulated
    row8 = next(line for line in md.splitlines() if line.startswith("| 8 |"))
    certified = row8.split("|")[2].split("/")[0].strip()
    assert certified in ("none", "0")  # never above the simulated boundary (0)
