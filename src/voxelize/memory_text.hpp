// voxfx — how the tiles' and the sparse grid's budget messages write bytes (internal).
#pragma once

#include <cstdint>
#include <string>

namespace voxfx::detail {

/// "1.50 GiB" from 1 GiB up, "64.0 MiB" below (defined in voxelize/tiled.cpp).
std::string memoryText(uint64_t bytes);

} // namespace voxfx::detail
