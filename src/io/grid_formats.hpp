// voxfx — the grid file formats behind grid_io.hpp (internal). Writers take an orthographic,
// uniformly sliced grid (writeGrid prepares it); readers take the file's bytes and
// throw voxfx::Error with the cause only: readGrid prefixes the path.
#pragma once

#include <bit>
#include <cstdint>
#include <functional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/sparse_grid.hpp"

namespace voxfx::detail {

// Binary formats (binvox bytes, NRRD raw uint8, PLY binary_little_endian, the byte-expansion
// tables) are written straight from memory.
static_assert(std::endian::native == std::endian::little, "voxfx io assumes a little-endian host");

/// The whole file at `path` (a grid or level-set file); voxfx::Error naming the path when it is a
/// directory, cannot be opened or comes back short.
std::vector<uint8_t> readFileBytes(const std::string& path);

void writeBinvox(const VoxelGrid& grid, std::ostream& out);
/// The same file in slabs along world x, for grids that are not held densely: the header of
/// `frame` (world dims `n`), then cells(x0, x1) for x0 = 0, slab, 2 slab, ...: the cells
/// [x0, x1) x [0, ny) x [0, nz) as a grid of that size (any slicing axis; its box is not read).
/// Byte for byte writeBinvox of the whole grid (one run-length encoder carried across slabs).
void writeBinvoxSlabs(const Frame& frame, const Vec3i& n, int64_t slab,
                      const std::function<VoxelGrid(int64_t, int64_t)>& cells, std::ostream& out);
VoxelGrid readBinvox(std::span<const uint8_t> bytes);

/// Writes through the temporary file's path (OpenVDB opens files by name).
void writeVdb(const VoxelGrid& grid, AtomicFile& file, const GridWriteOptions& options);
/// `release`, when given, is the buffer holding `bytes`: it is emptied (its memory returned) once
/// OpenVDB has parsed them, before the grid is allocated, so the file and the grid are not both
/// held at the peak.
VoxelGrid readVdb(std::span<const uint8_t> bytes, std::vector<uint8_t>* release = nullptr);

/// The sparse grid's tree as a .vdb (no dense grid), through the temporary file's path.
void writeSparseVdb(const SparseGrid& grid, AtomicFile& file, const GridWriteOptions& options);
/// A .vdb file's bytes as a sparse grid (checked and read as readVdb).
SparseGrid readSparseVdb(std::span<const uint8_t> bytes);

void writeNrrd(const VoxelGrid& grid, std::ostream& out);
/// As writeBinvoxSlabs, in slabs along world z (NRRD's slowest axis): cells(z0, z1) are the cells
/// [0, nx) x [0, ny) x [z0, z1). Byte for byte writeNrrd of the whole grid.
void writeNrrdSlabs(const Frame& frame, const Vec3i& n, int64_t slab,
                    const std::function<VoxelGrid(int64_t, int64_t)>& cells, std::ostream& out);
VoxelGrid readNrrd(std::span<const uint8_t> bytes);

/// format: GridFormat::Ply or GridFormat::Obj.
void writeVoxelMesh(const VoxelGrid& grid, std::ostream& out, GridFormat format);

/// Shortest decimal text that reads back as the same double (std::to_chars).
std::string formatDouble(double v);

/// A NumPy .npy 1.0 header: magic, length, the dict padded to a multiple of 64 bytes; Fortran
/// order unless `fortranOrder` is false (C order). `descr` e.g. "<f4", `shape` e.g.
/// "(3, 16, 16, 16)". The data follows.
void writeNpyHeader(std::ostream& out, const std::string& descr, const std::string& shape,
                    bool fortranOrder = true);

/// .npy: the occupancy as a bool array [x, y, z] in C order; .npz: a deflated zip of it
/// ("occupancy") with "origin" and "cell_size" (float64 (3,)), as np.savez_compressed writes one.
void writeGridNpy(const VoxelGrid& grid, std::ostream& out);
void writeGridNpz(const VoxelGrid& grid, std::ostream& out);

} // namespace voxfx::detail
