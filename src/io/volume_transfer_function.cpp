// voxfx — reading a transfer function's JSON file (parsing lives in render/transfer_function.cpp).
#include <string_view>

#include "io/volume_formats.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx {

TransferFunction loadTransferFunction(const std::string& path) {
    const std::vector<uint8_t> bytes = detail::readVolumeFile(path);
    return parseTransferFunction(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                                 path);
}

} // namespace voxfx
