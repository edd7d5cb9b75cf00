// voxfx — fuzz target: the CSG expression parser (functional and JSON syntax). An accepted
// expression must print to a canonical form that parses back to the same form.
#include "fuzz_target.hpp"
#include "voxfx/csg.hpp"

VOXFX_FUZZ_TARGET(csg) {
    voxfx::fuzz::expectCleanError([&] {
        const voxfx::CsgNode node = voxfx::parseCsgExpression(voxfx::fuzz::asText(data));
        const std::string canonical = voxfx::toString(node);
        voxfx::CsgNode again;
        try {
            again = voxfx::parseCsgExpression(canonical);
        } catch (const voxfx::Error&) { voxfx::fuzz::require(false, "the canonical form parses"); }
        voxfx::fuzz::require(voxfx::toString(again) == canonical, "the canonical form is a fixed point");
    });
}
