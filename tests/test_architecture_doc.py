"""docs/architecture.md's file table names every module of the package (issue 37: it left out 25,
all of mtbmj/bike/ among them), so the map a new developer reads first is the whole house."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _table_rows() -> dict[str, str]:
    text = (ROOT / "docs" / "architecture.md").read_text()
    section = text.split("## Where each file lives", 1)[1]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")] if line.startswith("|") else []
        if len(cells) >= 2 and cells[0] not in ("path", "---"):
            rows[cells[0]] = cells[1]
    return rows


def test_every_module_is_in_the_file_table():
    rows = _table_rows()
    missing = []
    for folder in ("mtbmj", "controllers", "validation"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT)
            if path.name == "__init__.py" and rel.as_posix() != "mtbmj/__init__.py":
                continue  # a package's marker and exports: its folder's row stands for it
            parent = f"`{rel.parent.as_posix()}/`"
            if rel.parent.name == "presets" and rel.parent.parent.name == "bike":
                parent = "`mtbmj/bike/`"
            named = [f"`{rel.as_posix()}`" in path_cell for path_cell in rows]
            in_folder_row = parent in rows and re.search(rf"`{re.escape(path.name)}`", rows[parent])
            in_path_cell = any(named)
            if not (in_folder_row or in_path_cell):
                missing.append(rel.as_posix())
    assert not missing, f"docs/architecture.md's file table does not name: {', '.join(missing)}"
