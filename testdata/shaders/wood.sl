// wood: the growth rings of a log cut lengthwise, seen on a plank. The distance from the
// log's axis (running along v) sets the ring; noise bends the rings and adds fine grain along
// the fibres. Re-expressed after the RenderMan Companion's wood shader (ch. 16).
shader wood(float ringscale = 12,
            float swirl = 0.12,
            float grain = 0.25,
            color light = color(0.72, 0.47, 0.26),
            color dark = color(0.36, 0.2, 0.09)) {
    // Position in the log's cross-section: x across the plank, z the plank's depth.
    float x = (u - 0.5) * 2 + swirl * snoise(point(u * 3, v * 3, 0.7));
    float z = 0.35 + 0.1 * snoise(point(v * 2, 1.3, u * 2));
    float r = sqrt(x * x + z * z) * ringscale;
    // Fine grain: stretched along the fibres (v).
    r = r + grain * snoise(point(u * 40, v * 4, 0.2));
    float ring = mod(r, 1);
    // Early wood (light) grows slowly darker; a sharp edge to the next year's ring.
    float t = smoothstep(0, 0.8, ring) - smoothstep(0.83, 1, ring);
    Ci = mix(light, dark, t);
}
