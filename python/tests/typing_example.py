"""A small typed program that mypy --strict checks against the package's stubs
(scripts/check-pip.sh); not a test of its own (pytest collects nothing here)."""
from pathlib import Path

import numpy as np
import numpy.typing as npt

import voxfx


def occupancy(path: Path, points: npt.NDArray[np.float64]) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.bool_]]:
    mesh = voxfx.load_mesh(path)
    grid: voxfx.Grid = voxfx.voxelize(mesh, resolution=64, cube=True, padding=2)
    inside = voxfx.contains(mesh, points, method="winding")
    both = grid | voxfx.voxelize(mesh, like=grid, mode="surface")
    return both.indices(), inside


if __name__ == "__main__":
    print(occupancy(Path("bunny.off"), np.zeros((4, 3))))
