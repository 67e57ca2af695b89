// marble: blue marble. Turbulence displaces a sine-wave stratification; a colour spline maps
// the result to white stone with blue veins. After the RenderMan Companion's blue marble
// shader (ch. 16), re-expressed.
shader marble(float scale = 2,
              float veining = 3,
              float distortion = 0.7,
              float octaves = 5) {
    float t = turbulence(P * scale, octaves, 2, 0.5);
    float layer = sin((u + v * 0.3 + distortion * t) * veining * 3.14159265);
    float s = clamp(0.5 + 0.5 * layer, 0, 1);
    Ci = spline(s,
                color(0.25, 0.25, 0.35),
                color(0.25, 0.25, 0.35),
                color(0.20, 0.20, 0.30),
                color(0.20, 0.20, 0.30),
                color(0.20, 0.20, 0.30),
                color(0.25, 0.25, 0.35),
                color(0.25, 0.25, 0.35),
                color(0.15, 0.15, 0.26),
                color(0.15, 0.15, 0.26),
                color(0.10, 0.10, 0.20),
                color(0.10, 0.10, 0.20),
                color(0.25, 0.25, 0.35),
                color(0.10, 0.10, 0.20)) * 3;
}
