// eroded: corroded metal. A fractal sum of |noise| decides where the surface is eaten away
// (rust) and where bare metal remains, with a soft transition. In the spirit of the RenderMan
// Companion's eroded shader (ch. 16), which erodes opacity; here the result is baked as colour.
shader eroded(float erosion = 0.75,
              float scale = 4,
              color metal = color(0.62, 0.6, 0.58),
              color rust = color(0.35, 0.15, 0.06)) {
    point pp = P * scale;
    float m = 0;
    float f = 1;
    for (float i = 0; i < 5; i += 1) {
        m += abs(snoise(pp * f)) / f;
        f *= 2;
    }
    float eaten = smoothstep(erosion - 0.08, erosion + 0.08, m);
    Ci = mix(metal, rust, eaten) * (0.7 + 0.3 * m);
}
