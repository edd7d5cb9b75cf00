// voxfx — umbrella header: every public header of the library, by layer (docs/ARCHITECTURE.md).
// The layering test (tests/test_layering.cpp) checks that it names every one of them.
// Thread-safety: see each header; as a rule, const objects may be shared between threads and
// nothing in the library keeps global mutable state.
#pragma once

// core: math, meshes, frames, the slicemap, grids, volumes, errors, threads.
#include "voxfx/bitgrid.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/image.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/text.hpp"
#include "voxfx/types.hpp"
#include "voxfx/volume.hpp"
#include "voxfx/voxel_grid.hpp"

// raster: the fragment rasterizer and fragment lists.
#include "voxfx/fragment_list.hpp"
#include "voxfx/raster.hpp"

// voxelize: surface, solid and attribute voxelization, the device choice, point occupancy.
#include "voxfx/attribute_grid.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/device.hpp"
#include "voxfx/threshold.hpp"
#include "voxfx/tiled.hpp"
#include "voxfx/voxelize.hpp"

// grid: the bit-grid toolkit (GI08): density, normals, morphology, CSG, queries, meshing, smoke;
// closest points and signed distance fields.
#include "voxfx/csg.hpp"
#include "voxfx/dda.hpp"
#include "voxfx/density.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/intersection_volume.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/surface_mesh.hpp"
#include "voxfx/surface_sampling.hpp"
#include "voxfx/vertex_colors.hpp"

// scene: scenes, lights, cameras, materials, light views, transfer functions, volume scenes; the
// shadow techniques' options and counters.
#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/transfer_function.hpp"
#include "voxfx/volume_scene.hpp"

// dsm: deep shadow maps (visibility functions, storage, maps from lights), walking volume scenes.
#include "voxfx/deep_shadow.hpp"
#include "voxfx/dsm.hpp"
#include "voxfx/segment_walker.hpp"

// render: the renderer (G-buffer, passes), its shadow techniques and glass methods, one room each,
// environment light and the exact tracer.
#include "voxfx/absorption_shadow.hpp"
#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/exact_glass.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/frosted_glass.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/glass_options.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/shadow_map.hpp"
#include "voxfx/shadow_volume.hpp"
#include "voxfx/translucency_shadow.hpp"
#include "voxfx/transmittance_shadow.hpp"
#include "voxfx/triangle_tracer.hpp"
#include "voxfx/voxel_glass.hpp"

// sim: particles, the moving obstacle.
#include "voxfx/moving_obstacle.hpp"
#include "voxfx/particles.hpp"

// view: interactive viewing: camera moves, previews, the options as a scene file's settings.
#include "voxfx/view.hpp"

// io: every function that reads or writes a file.
#include "voxfx/attribute_io.hpp"
#include "voxfx/environment_io.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/level_set.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/particles_io.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/sdf_io.hpp"
#include "voxfx/sparse_grid.hpp"
#include "voxfx/volume_io.hpp"
#include "voxfx/volume_to_mesh.hpp"

// batch: many meshes in one process.
#include "voxfx/batch.hpp"
