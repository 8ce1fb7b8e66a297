"""laspy's own sample LAS/LAZ files: real aerial LiDAR that nobody here wrote, for the tests.

They are not in laspy's wheel, only in its source archive (``tests/data``), so :func:`laspy_sample`
fetches that archive once with pip, for the laspy version installed, and keeps the files in a
cache folder (``$CURV_TEST_DATA``, else ``~/.cache/curvlab-tests``). A test that needs them is
skipped, saying why, when neither laspy nor the archive can be had (no network).

The files used (laspy 2.x; BSD licence, as laspy):

- ``autzen_trim.laz``: 110,000 points of Autzen stadium (Oregon), ground, roofs, walls and trees;
- ``vegetation_1_3.las``: 10,683 points of a few trees;
- ``simple1_4.las``: 22,600 points of a built-up area;
- ``plane.laz``: 28,185 points of a 2 m plane, coordinates on a 1 cm grid (35 % coincident).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import pytest

__all__ = ["laspy_sample", "SAMPLES"]

SAMPLES = ("autzen_trim.laz", "vegetation_1_3.las", "simple1_4.las", "plane.laz")
"""The aerial scans the orientation and quantisation tests read."""


def _folder() -> Path:
    laspy = pytest.importorskip("laspy")
    pytest.importorskip("lazrs")
    root = Path(os.environ.get("CURV_TEST_DATA") or Path.home() / ".cache" / "curvlab-tests")
    return root / f"laspy-{laspy.__version__}"


def _fetch(folder: Path) -> None:
    """Unpack the sample files of laspy's source archive into ``folder``."""
    import laspy

    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "pip", "download", f"laspy=={laspy.__version__}", "--no-binary", ":all:",
               "--no-deps", "--quiet", "-d", tmp]
        try:
            subprocess.run(cmd, check=True, capture_output=True, timeout=300)
        except (subprocess.SubprocessError, OSError) as exc:
            pytest.skip(f"laspy's source archive (its sample LAS files) could not be fetched: {exc}")
        archive = next(Path(tmp).glob("laspy-*.tar.gz"))
        folder.mkdir(parents=True, exist_ok=True)
        with tarfile.open(archive) as tar:
            for member in tar.getmembers():
                name = Path(member.name)
                if name.parent.name == "data" and name.suffix in (".las", ".laz") and member.isfile():
                    data = tar.extractfile(member).read()
                    part = folder / (name.name + ".part")
                    part.write_bytes(data)
                    part.replace(folder / name.name)  # whole files only, also with two test processes


def laspy_sample(name: str) -> Path:
    """The path of one of laspy's sample files (fetched on first use; the test is skipped without
    network or laspy)."""
    folder = _folder()
    path = folder / name
    if not path.exists():
        _fetch(folder)
    if not path.exists():
        pytest.fail(f"laspy {folder.name}'s source archive has no tests/data/{name}")
    return path
