// voxfx — fuzz target: the OBJ mesh reader (io/mesh_obj.cpp).
#include "fuzz_mesh.hpp"

VOXFX_FUZZ_TARGET(obj) { voxfx::fuzz::fuzzMeshParser(data, "fuzz.obj", voxfx::detail::parseObj); }
