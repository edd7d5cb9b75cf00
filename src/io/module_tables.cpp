// voxfx — the typed tables of the I/O modules, loaded through core/module_loader on first use.
#include "core/module_loader.hpp"
#include "io/module_api.hpp"
#include "voxfx/error.hpp"

namespace voxfx::detail {

namespace {
template <class Table> const Table& load(const char* name, const char* purpose) {
    const auto* table = static_cast<const Table*>(loadModule(name, kModuleAbi, purpose));
    if (table->abi != kModuleAbi || table->size != sizeof(Table))
        fail("module voxfx_", name,
             ".so is from another voxfx build (its table does not match this library)");
    return *table;
}
} // namespace

// Function-local statics: loaded once, thread-safe, and retried after a failure (a throwing
// initializer leaves the static uninitialized).
const VdbModule& vdbModule() {
    static const VdbModule& table = load<VdbModule>("vdb", "for OpenVDB .vdb files");
    return table;
}

void prefetchVdbModule() { prefetchModule("vdb", kModuleAbi); }

const AssimpModule& assimpModule() {
    static const AssimpModule& table = load<AssimpModule>("assimp", "for glTF and the formats Assimp reads");
    return table;
}

const ExrModule& exrModule() {
    static const ExrModule& table = load<ExrModule>("exr", "for OpenEXR .exr images");
    return table;
}

} // namespace voxfx::detail
