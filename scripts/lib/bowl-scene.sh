# Sourced by scripts that bake the large transfer scene. bowl_scene RINGS SEGMENTS writes, as OBJ
# on stdout, a bowl (the lower unit hemisphere, normals facing its inside, RINGS × SEGMENTS quads)
# holding a ball of radius 0.35 (a UV sphere of as many rings and segments), with normals: about
# 100 000 vertices at 125 × 400 (scripts/transfer-results.sh, scripts/visibility-vs-embree.sh).
bowl_scene() {
  local rings=$1 segments=$2
  awk -v rings="$rings" -v segs="$segments" '
  BEGIN {
    pi = atan2(0, -1)
    for (r = 0; r <= rings; r++) {
      th = pi / 2 + pi / 2 * r / rings
      for (s = 0; s < segs; s++) {
        ph = 2 * pi * s / segs; x = sin(th) * cos(ph); y = sin(th) * sin(ph); z = cos(th)
        printf "v %.7f %.7f %.7f\nvn %.7f %.7f %.7f\n", x, y, z, -x, -y, -z
      }
    }
    for (r = 0; r < rings; r++) for (s = 0; s < segs; s++) {
      a = r * segs + s + 1; b = (r + 1) * segs + s + 1
      c = (r + 1) * segs + (s + 1) % segs + 1; d = r * segs + (s + 1) % segs + 1
      printf "f %d//%d %d//%d %d//%d\nf %d//%d %d//%d %d//%d\n", a, a, b, b, c, c, a, a, c, c, d, d
    }
    base = (rings + 1) * segs; cx = 0.2; cz = -0.6; R = 0.35
    printf "v %.7f 0 %.7f\nvn 0 0 1\n", cx, cz + R
    for (r = 1; r < rings; r++) {
      th = pi * r / rings
      for (s = 0; s < segs; s++) {
        ph = 2 * pi * s / segs; x = sin(th) * cos(ph); y = sin(th) * sin(ph); z = cos(th)
        printf "v %.7f %.7f %.7f\nvn %.7f %.7f %.7f\n", cx + R * x, R * y, cz + R * z, x, y, z
      }
    }
    printf "v %.7f 0 %.7f\nvn 0 0 -1\n", cx, cz - R
    top = base + 1; bottom = base + 2 + (rings - 1) * segs
    for (s = 0; s < segs; s++) {
      p = base + 2 + s; q = base + 2 + (s + 1) % segs
      printf "f %d//%d %d//%d %d//%d\n", top, top, p, p, q, q
      p = base + 2 + (rings - 2) * segs + s; q = base + 2 + (rings - 2) * segs + (s + 1) % segs
      printf "f %d//%d %d//%d %d//%d\n", bottom, bottom, q, q, p, p
    }
    for (r = 1; r < rings - 1; r++) for (s = 0; s < segs; s++) {
      a = base + 2 + (r - 1) * segs + s; b = base + 2 + r * segs + s
      c = base + 2 + r * segs + (s + 1) % segs; d = base + 2 + (r - 1) * segs + (s + 1) % segs
      printf "f %d//%d %d//%d %d//%d\nf %d//%d %d//%d %d//%d\n", a, a, b, b, c, c, a, a, c, c, d, d
    }
  }'
}
