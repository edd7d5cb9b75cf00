// voxfx — umbrella header: everything a client of the library (such as the voxfx command) needs.
// Thread-safety: see each header; as a rule, const objects may be shared between threads and
// nothing in the library keeps global mutable state.
#pragma once

// Meshes, frames, the slicemap and voxelization.
#include "voxfx/batch.hpp"
#include "voxfx/bitgrid.hpp"
#include "voxfx/device.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

// The bit-grid toolkit (GI08): density, normals, morphology, CSG, queries, particles, meshing.
#include "voxfx/csg.hpp"
#include "voxfx/dda.hpp"
#include "voxfx/density.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/moving_obstacle.hpp"
#include "voxfx/particles.hpp"
#include "voxfx/particles_io.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/sdf_io.hpp"
#include "voxfx/surface_mesh.hpp"

// Rendering: scenes, images, shadows (ED06 transmittance, CHANG absorption).
#include "voxfx/attribute_grid.hpp"
#include "voxfx/demo.hpp"
#include "voxfx/image.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow.hpp"
