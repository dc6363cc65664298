"""The validation report opens in a real browser with no network: headless Chromium loads it from
disk, a probe script added to a copy of the page records whether every figure decoded (its
natural size) and what the tables hold, and ``--dump-dom`` hands that back."""

import pytest

from mtbmj.validation.report import run_validation
from mtbmj.measured.sled import example_path

from helpers import CHROMIUM, rendered


@pytest.mark.skipif(not CHROMIUM.exists(), reason="headless Chromium not installed (/usr/bin/chromium; "
                                                  "apt-get install -y chromium)")
def test_report_renders_in_headless_chromium(tmp_path):
    validation = run_validation(example_path(), ["S11", "S12"], duration=1.0)
    written = validation.write(tmp_path / "report")
    page = tmp_path / "report" / "validation_report.html"
    pngs = sorted(p.name for p in written if p.suffix == ".png")
    result, _ = rendered(page, tmp_path)
    assert sorted(i["id"] for i in result["imgs"]) == pngs
    for image in result["imgs"]:
        assert image["inline"] and image["complete"] and image["width"] > 0 and image["height"] > 0, image
    assert result["resources"] == []  # nothing fetched: self-contained
    metrics = result["tables"]["metrics"]
    assert metrics["visible"] and metrics["rows"] == 1 + len(validation.configs) and metrics["cells"] == 2 * 18
    assert {"meta", "metrics", "timing", "rms", "flags"} <= set(result["tables"])
