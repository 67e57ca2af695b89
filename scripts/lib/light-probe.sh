# Sourced by the reproduction scripts after scripts/lib/common.sh: sets $env to the Grace Cathedral
# probe of the shared test data, or, when that is absent, to a procedural sky baked into "$tmp" by
# sample-shader (512x256; 128x64 when small). Needs $bin (from `build`) and $tmp (a scratch
# directory).
env=../shared/testdata/envmaps/grace_probe_250.pfm
if [ ! -f "$env" ]; then
    echo "$(basename "$0"): $env absent; using the procedural sky" >&2
    size=512x256
    if [ "$small" = 1 ]; then size=128x64; fi
    "$bin/sample-shader" testdata/shaders/sky.sl --latlong "$size" --tolerance 0.05 -o "$tmp/sky.exr" -q
    env="$tmp/sky.exr"
fi
