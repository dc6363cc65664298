"""Every run's manifest names the code that made it (issue 50 item 7): the digest of mtbmj's own
sources beside the versions of MuJoCo, numba and the numeric stack."""
from __future__ import annotations

import hashlib
import json
import sys

import mujoco
import pytest

from mtbmj import result


@pytest.fixture
def scratch_package(tmp_path, monkeypatch):
    pkg = tmp_path / "provscratch"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "law.py").write_text("K = 1.0\n")
    (pkg / "scene.xml").write_text("<mujoco/>\n")
    (pkg / "notes.txt").write_text("not a source\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(result, "_SOURCE_PACKAGES", ("provscratch",))
    result.source_digest.cache_clear()
    yield pkg
    result.source_digest.cache_clear()
    sys.modules.pop("provscratch", None)


def test_the_digest_is_the_sources_hashed_in_order(scratch_package):
    # the digest written out here by hand: each source named by package and path, then its bytes
    h = hashlib.sha256()
    for rel, body in (("__init__.py", b""), ("scene.xml", b"<mujoco/>\n"), ("sub/law.py", b"K = 1.0\n")):
        h.update(f"provscratch/{rel}".encode() + b"\0")
        h.update(body + b"\0")
    assert result.source_digest() == h.hexdigest()


def test_an_edit_of_a_source_changes_the_digest_and_other_files_do_not(scratch_package):
    before = result.source_digest()
    (scratch_package / "notes.txt").write_text("edited\n")
    result.source_digest.cache_clear()
    assert result.source_digest() == before  # not a source
    (scratch_package / "sub" / "law.py").write_text("K = 1.5\n")
    result.source_digest.cache_clear()
    assert result.source_digest() != before


def test_a_runs_manifest_records_the_digest_and_versions(tmp_path):
    from mtbmj import cli

    assert cli.main(["drop", "S1", "--out", str(tmp_path / "s1"), "--quiet"]) == 0
    v = json.loads((tmp_path / "s1" / "manifest.json").read_text())["versions"]
    assert v["mujoco"] == mujoco.__version__
    assert len(v["mtbmj_source_sha256"]) == 64 and v["mtbmj_source_sha256"] == result.source_digest()
    numba = pytest.importorskip("numba")
    assert v["numba"] == numba.__version__
