# Sourced by the ring-free tables (ring-free-table.sh, windows-table.sh) after scripts/lib/common.sh:
# builds the binaries and the example named in $1, renders the demo sky into the reference cache
# once, and sets
#   cache   the cache of angular references, target/ring-free/ (shared by both tables)
#   probes  every shared light probe and the demo sky, as the examples take them.
build_ring_free() {
  local shared=../shared/testdata/envmaps
  cache=target/ring-free
  mkdir -p "$cache"
  require_shared envmaps
  build --bin sample-shader --example "$1"
  if [ ! -f "$cache/sky.exr" ]; then
    "$bin/sample-shader" testdata/shaders/sky.sl --latlong 512x256 --tolerance 0.05 -o "$cache/sky.exr" -q
  fi
  probes=(
    "$shared/grace_latlong.exr"
    "$shared/dxsdk_cubes/grace" "$shared/dxsdk_cubes/rnl" "$shared/dxsdk_cubes/stpeters" "$shared/dxsdk_cubes/galileo"
    "$shared/uffizi_ict_latlong_256x128.hdr"
    "$cache/sky.exr"
  )
}
