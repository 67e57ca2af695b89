// screen: a woven wire screen. Thin metal wires run along u and v; between them the gaps show a
// dark backing. `density` is the fraction of each cell covered by a wire (in the spirit of the
// RenderMan Companion's screen shader, ch. 16, which makes the gaps transparent; here the
// opacity is baked as colour). The wires get a soft cylindrical highlight across their width.
shader screen(float density = 0.25,
              float frequency = 8,
              color metal = color(0.85, 0.82, 0.75),
              color gap = color(0.04, 0.04, 0.05)) {
    float su = mod(u * frequency, 1);
    float sv = mod(v * frequency, 1);
    if (su < density || sv < density) {
        // Across the wire, a cosine lobe: brightest on the wire's axis.
        float across = min(su, sv) / density;
        Ci = metal * (0.6 + 0.4 * sin(3.14159265 * across));
    } else {
        Ci = gap;
    }
}
