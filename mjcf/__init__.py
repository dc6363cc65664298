"""MJCF scenes shipped with mtbmj (installed as ``mtbmj.mjcf``)."""
from pathlib import Path

DIRECTORY = Path(__file__).resolve().parent


def path(name: str) -> Path:
    """Path of a bundled MJCF file, e.g. ``path("drop_scene.xml")``."""
    return DIRECTORY / name


def scenes() -> list[Path]:
    """Every bundled scene file (``*scene*.xml``)."""
    return sorted(DIRECTORY.glob("*scene*.xml"))
