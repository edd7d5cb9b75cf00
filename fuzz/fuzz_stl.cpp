// voxfx — fuzz target: the STL mesh reader (io/mesh_stl.cpp).
#include "fuzz_mesh.hpp"

VOXFX_FUZZ_TARGET(stl) { voxfx::fuzz::fuzzMeshParser(data, "fuzz.stl", voxfx::detail::parseStl); }
