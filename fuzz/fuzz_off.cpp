// voxfx — fuzz target: the OFF mesh reader (io/mesh_off.cpp).
#include "fuzz_mesh.hpp"

VOXFX_FUZZ_TARGET(off) { voxfx::fuzz::fuzzMeshParser(data, "fuzz.off", voxfx::detail::parseOff); }
