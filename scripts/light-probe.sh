# Sourced by the reproduction scripts: sets $env to the Grace Cathedral probe of the shared test
# data, or, when that is absent, to a procedural sky baked into "$tmp" by sample-shader.
# Needs $bin (the release binaries) and $tmp (a scratch directory).
env=../shared/testdata/envmaps/grace_probe_250.pfm
if [ ! -f "$env" ]; then
    echo "$(basename "$0"): $env absent; using the procedural sky" >&2
    "$bin/sample-shader" testdata/shaders/sky.sl --latlong 512x256 --tolerance 0.05 -o "$tmp/sky.exr" -q
    env="$tmp/sky.exr"
fi
