// voxfx — fuzz target: the PLY mesh reader (io/mesh_ply.cpp).
#include "fuzz_mesh.hpp"

VOXFX_FUZZ_TARGET(ply) { voxfx::fuzz::fuzzMeshParser(data, "fuzz.ply", voxfx::detail::parsePly); }
