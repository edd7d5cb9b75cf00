// voxfx — umbrella header: everything a client of the library (such as the voxfx command) needs.
#pragma once

#include "voxfx/bitgrid.hpp"
#include "voxfx/error.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"
