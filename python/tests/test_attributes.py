"""voxfx.attributes (`voxfx attributes` from Python) and per-vertex colours: the loaders' colours
against the files' text read here, a linear colour field whose per-voxel mean is known in closed
form, a real COFF mesh's uniform colour, the attribute channels against a surface voxelization and
a sphere's radial normals, and the arrays against what the command writes.
"""
import pickle
import struct
import subprocess

import numpy as np
import pytest

import voxfx


def off_colours(path):
    """The vertex colours of a COFF file read here: the 3 values after x y z, over 255 when they are
    integers (no '.')."""
    lines = [l.split("#")[0].split() for l in open(path)]
    lines = [l for l in lines if l]
    assert lines[0][0] == "COFF"
    nv = int(lines[1][0])
    out = []
    for l in lines[2:2 + nv]:
        c = l[3:6]
        out.append([float(x) / (255 if "." not in "".join(c) else 1) for x in c])
    return np.array(out, np.float32)


def test_coff_and_ply_colours_load_as_the_files_hold_them(data_path, tmp_path):
    for name in ("meshes/mesh_with_colors.off", "meshes/cactus.off"):
        mesh, colours = voxfx.load_colored_mesh(data_path(name))
        assert colours.shape == (mesh.vertex_count, 3)
        assert np.allclose(colours, off_colours(data_path(name)), atol=1e-7)
    mesh, colours = voxfx.load_colored_mesh(data_path("meshes/colored_tetra.ply"))
    assert np.allclose(colours * 255, [[255, 255, 0], [0, 255, 255], [128, 0, 255], [255, 128, 0]])
    assert voxfx.load_colored_mesh(data_path("meshes/bunny00.off"))[1] is None
    # Binary PLY: uchar colours over 255, float colours as they are.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    for ctype, fmt, values in (("uchar", "B", [10, 20, 30]), ("float", "f", [0.25, 0.5, 2.0])):
        head = (f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                f"property float z\nproperty {ctype} red\nproperty {ctype} green\nproperty {ctype} blue\n"
                f"element face 1\nproperty list uchar int vertex_indices\nend_header\n").encode()
        body = b"".join(struct.pack("<fff", *p) + struct.pack("<" + fmt * 3, *values) for p in v)
        body += struct.pack("<Biii", 3, 0, 1, 2)
        (tmp_path / "c.ply").write_bytes(head + body)
        _, c = voxfx.load_colored_mesh(tmp_path / "c.ply")
        scale = 255 if ctype == "uchar" else 1
        assert np.allclose(c, np.array([values] * 3) / scale)
    (tmp_path / "bad.off").write_text("COFF\n3 1 0\n0 0 0 1 0\n1 0 0 1 0 0\n0 1 0 1 0 0\n3 0 1 2\n")
    with pytest.raises(voxfx.Error, match=r"bad\.off:3: vertex 0: expected 3 or 4 colour components"):
        voxfx.load_colored_mesh(tmp_path / "bad.off")


def test_a_linear_colour_field_averages_to_its_value_at_each_voxel_centre():
    # A flat mesh at z = 0.3 (a 6 x 6 grid of vertices, triangulated), colours linear in position:
    # the colour at the point nearest a voxel centre is the field there, and every write into a voxel
    # of this plane (seen along z) is at the column centre's (x, y): the mean is A (x, y, 0.3) + b.
    xs = np.linspace(0, 1, 6)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.full(X.size, 0.3)], axis=1)
    quads = [(i * 6 + j, (i + 1) * 6 + j, (i + 1) * 6 + j + 1, i * 6 + j + 1) for i in range(5) for j in range(5)]
    f = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    A = np.array([[0.5, 0.1, 0.0], [0.0, 0.7, 0.0], [0.2, 0.2, 0.0]])
    b = np.array([0.1, 0.05, 0.3])
    colours = v @ A.T + b
    grid = voxfx.attributes((v, f), colors=colours, channels="count,color", bounds=(0, 0, 0, 1, 1, 1), dims=(10, 10, 10),
                            margin=0)
    written = grid.color_count > 0
    assert written.sum() == 100 and np.array_equal(written, grid.count > 0)
    ijk = np.argwhere(written)
    centres = ijk @ grid.affine[:3, :3].T + grid.affine[:3, 3]
    centres[:, 2] = 0.3
    assert np.abs(grid.color[written] - (centres @ A.T + b)).max() < 1e-6
    assert (grid.color[~written] == 0).all()


def test_a_real_coloured_mesh_keeps_its_uniform_colour(data_path):
    grid = voxfx.attributes(data_path("meshes/cactus.off"), resolution=48)
    assert "color" in grid.channels
    written = grid.color_count > 0
    assert written.any()
    assert np.abs(grid.color[written] - 192 / 255).max() < 1e-6
    conservative = voxfx.attributes(data_path("meshes/cactus.off"), resolution=48, coverage="conservative",
                                    channels=["color"])
    assert (conservative.color_count > 0).sum() >= written.sum()


def test_attribute_channels_match_a_surface_voxelization_and_a_spheres_normals(data_path):
    path = data_path("meshes/sphere.off")
    grid = voxfx.attributes(path, resolution=40, margin=1)
    assert grid.channels == ("count", "normal", "material", "ior")
    # The cells written are the surface voxelization's (the same centre-sampled fragments, ED06).
    surface = voxfx.voxelize(voxfx.load_mesh(path), resolution=40, margin=1, mode="surface").to_numpy()
    assert np.array_equal(grid.count > 0, surface)
    assert np.array_equal(grid.occupancy(), surface)
    assert (grid.material[surface] == 0).all() and (grid.material[~surface] == -1).all()
    assert np.allclose(grid.ior[surface], 1.5) and (grid.ior[~surface] == 0).all()
    # Normals: the unit average of faces' normals near each voxel, about radial on a sphere
    # (its 320 faces are 20 degrees across; a voxel's faces are within a few degrees of its centre's
    # radial direction).
    mesh = voxfx.load_mesh(path)
    centre = np.mean(mesh.bounds, axis=0)
    ijk = np.argwhere(surface)
    radial = ijk @ grid.affine[:3, :3].T + grid.affine[:3, 3] - centre
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    cosine = np.einsum("ij,ij->i", grid.normal[surface], radial)
    assert cosine.min() > np.cos(np.radians(25))


def test_attributes_agree_with_the_command_and_save_as_it_writes(data_path, cli, tmp_path):
    path = data_path("meshes/elephant.off")
    grid = voxfx.attributes(path, resolution=48, channels="count,normal,ior")
    for channel in ("count", "normal", "ior"):
        out = tmp_path / f"cli_{channel}.npy"
        subprocess.run([cli, "attributes", path, "-o", str(out), "-r", "48", "--channels", channel, "-q"], check=True)
        from_cli = np.load(out)
        ours = grid[channel]
        if channel == "normal":  # the command writes (3, nx, ny, nz)
            ours = np.moveaxis(ours, 3, 0)
        assert np.array_equal(from_cli, ours), channel
        grid.save(tmp_path / f"py_{channel}.npy", channel=channel)
        saved = np.load(tmp_path / f"py_{channel}.npy")
        # The normal is normalized once more on the way out (a unit vector again, to float rounding).
        assert np.allclose(saved, from_cli, rtol=0, atol=2e-7) if channel == "normal" else np.array_equal(saved, from_cli)
    again = pickle.loads(pickle.dumps(grid))
    assert again.channels == grid.channels and np.array_equal(again.normal, grid.normal)
    with pytest.raises(voxfx.ArgumentError, match="color"):
        voxfx.attributes(path, channels="color")
    with pytest.raises(voxfx.ArgumentError, match="absorption"):
        voxfx.attributes(path, channels="absorption")
    with pytest.raises(AttributeError, match="channels: count, normal, ior"):
        grid.material
