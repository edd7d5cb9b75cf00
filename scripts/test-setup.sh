# Sourced by scripts/test.sh and scripts/sanitize.sh (not run on its own): installs the apt
# dependencies, fetches the test data, and sets what both test passes share: VOXFX_REQUIRE_DATA=1
# (a test whose data is missing fails instead of skipping), label_args from VOXFX_TEST_LABEL
# (default "fast"; "slow" or "" for the long cases), jobs, and the ccache launcher.
scripts/install-deps.sh
scripts/fetch-data.sh
export VOXFX_REQUIRE_DATA=1
label="${VOXFX_TEST_LABEL-fast}"
label_args=()
[ -n "$label" ] && label_args=(-L "$label")
jobs="$(nproc)"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
