"""The validation report opens in a real browser with no network: headless Chromium loads it from
disk, a probe script added to a copy of the page records whether every figure decoded (its
natural size) and what the tables hold, and ``--dump-dom`` hands that back."""
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from mtbmj.validation.report import run_validation
from mtbmj.measured.sled import example_path

CHROMIUM = Path("/usr/bin/chromium")
PROBE = """<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.map.call(document.images, function (i) {
    return {id: i.id, complete: i.complete, width: i.naturalWidth, height: i.naturalHeight,
            inline: i.src.indexOf('data:image/png;base64,') === 0};
  });
  var tables = {};
  Array.prototype.forEach.call(document.querySelectorAll('table'), function (t) {
    tables[t.id] = {rows: t.rows.length, cells: t.querySelectorAll('td').length,
                    visible: t.getBoundingClientRect().height > 0};
  });
  var resources = performance.getEntriesByType('resource').map(function (r) { return r.name; });
  var out = document.createElement('pre');
  out.id = 'render-check';
  out.textContent = JSON.stringify({imgs: imgs, tables: tables, resources: resources});
  document.body.appendChild(out);
});
</script>"""


def rendered(page, tmp_path) -> tuple[dict, str]:
    """(what the probe recorded, the DOM Chromium dumped) of ``page`` opened headless with no
    network, from a copy with the probe added (``tmp_path`` holds the copy and the profile)."""
    probe = tmp_path / "probe.html"
    probe.write_text(page.read_text().replace("</body>", PROBE + "</body>"))
    profile = tmp_path / "profile"
    command = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
               "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
               "--host-resolver-rules=MAP * ~NOTFOUND",  # no network at all
               "--virtual-time-budget=5000", "--dump-dom", probe.as_uri()]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    match = re.search(r'<pre id="render-check">(.*?)</pre>', done.stdout, re.S)
    assert match, f"no probe output (exit {done.returncode}): {done.stderr[-500:]}"
    return json.loads(match.group(1).replace("&quot;", '"').replace("&amp;", "&")), done.stdout


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
