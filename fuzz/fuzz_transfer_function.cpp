// voxfx — fuzz target: the transfer-function JSON parser (parseTransferFunction).
#include "fuzz_target.hpp"
#include "voxfx/transfer_function.hpp"

VOXFX_FUZZ_TARGET(transfer_function) {
    voxfx::fuzz::expectCleanError(
        [&] { (void)voxfx::parseTransferFunction(voxfx::fuzz::asText(data), "fuzz.json"); });
}
