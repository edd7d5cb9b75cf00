// voxfx — OpenVDB float and double grids as volumes, through the voxfx_vdb module (its readFloats
// holds the conventions: the index box, every voxel's value, the transform's checks).
//
// The grid's transform becomes the volume's placement: index (i, j, k) of the grid is the centre
// of a voxel, so the volume's voxel size is the transform's scale (per axis: non-uniform scales
// are kept) and its box starts half a voxel before the first index's centre. The dense size is
// checked against the voxel limit and the memory available before anything is allocated.
#include <exception>

#include "io/module_api.hpp"
#include "io/volume_formats.hpp"

namespace voxfx::detail {

namespace {

struct VdbVolumeTarget {
    const std::string* path;
    Volume volume;
    VdbFloatBox box;
    std::exception_ptr error; ///< what stopped the allocation (rethrown after the module returns)
    std::vector<uint8_t>* release = nullptr; ///< the file's bytes, emptied once parsed (see readVdb)
};

float* allocateVdbVolume(void* ctx, const VdbFloatBox& box) {
    auto& t = *static_cast<VdbVolumeTarget*>(ctx);
    try {
        // The module no longer reads the bytes (module_api.hpp): let them go before the volume comes.
        if (t.release) std::vector<uint8_t>().swap(*t.release);
        t.box = box;
        const Vec3i dims{box.dims[0], box.dims[1], box.dims[2]};
        const ScalarType type = box.isDouble ? ScalarType::Float64 : ScalarType::Float32;
        const std::string where = concat(*t.path, " (grid '", box.name, "')");
        checkedSampleBytes(dims, type, where);
        checkVolumeMemory(dims, 0, where);
        t.volume = Volume(dims, {box.lo[0], box.lo[1], box.lo[2]},
                          {box.spacing[0], box.spacing[1], box.spacing[2]}, type);
        const Vec3d axes[3] = {{box.axes[0][0], box.axes[0][1], box.axes[0][2]},
                               {box.axes[1][0], box.axes[1][1], box.axes[1][2]},
                               {box.axes[2][0], box.axes[2][1], box.axes[2][2]}};
        if (!(axes[0] == Vec3d{1, 0, 0} && axes[1] == Vec3d{0, 1, 0} && axes[2] == Vec3d{0, 0, 1})) try {
                t.volume.setAxes(axes[0], axes[1], axes[2]);
            } catch (const Error& e) { fail(where, ": ", e.what()); }
        return t.volume.values().data();
    } catch (...) {
        t.error = std::current_exception();
        return nullptr;
    }
}

} // namespace

Volume readVdbVolume(std::span<const uint8_t> bytes, const std::string& path, const std::string& gridName,
                     VolumeLoadReport& report, std::vector<uint8_t>* release) {
    report.fileBytes = bytes.size();
    const VdbModule& vdb = vdbModule();
    VdbVolumeTarget target{&path, {}, {}, nullptr, release};
    std::string error;
    const bool ok =
        vdb.readFloats(bytes.data(), bytes.size(), gridName.c_str(), &target, allocateVdbVolume, &error);
    if (target.error) std::rethrow_exception(target.error);
    if (!ok) fail(path, ": ", error);
    report.gridName = target.box.name;
    report.gridClass = target.box.gridClass;
    return std::move(target.volume);
}

} // namespace voxfx::detail
