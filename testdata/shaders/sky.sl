// sky: a procedural HDR sky for lat-long sampling (+Z up; D is the direction). Radiance is in
// relative physical units: the zenith about 1, the horizon brighter, a sun disc of angular
// radius `sun_radius` (radians) with radiance `sun_radiance`, a glow around it, soft clouds,
// and a dark ground below the horizon. Every term is non-negative.
shader sky(vector sun = vector(0.45, 0.25, 0.6),
           float sun_radius = 0.04,
           float sun_radiance = 2000,
           color zenith = color(0.35, 0.55, 1.1),
           color horizon = color(1.0, 1.05, 1.15),
           color ground = color(0.16, 0.14, 0.12),
           float clouds = 0.5) {
    vector s = normalize(sun);
    float cos_gamma = dot(D, s);
    float z = D.z;
    color c;
    if (z >= 0) {
        // Gradient from the zenith to a bright horizon.
        c = mix(zenith, horizon, pow(1 - z, 3));
        // Clouds: fbm in direction space, faded towards the horizon.
        float cover = smoothstep(0.05, 0.6, fbm(D * 3, 4, 2, 0.5) + clouds - 0.5);
        c = mix(c, color(1.3, 1.3, 1.35), 0.8 * cover * smoothstep(0, 0.2, z));
        // Glow (Mie-like forward scattering) and the sun's disc.
        c += color(1.0, 0.85, 0.6) * (6 * exp(40 * (cos_gamma - 1)));
        c += color(1.0, 0.95, 0.88) * sun_radiance * smoothstep(cos(sun_radius * 1.1), cos(sun_radius), cos_gamma);
    } else {
        c = ground * (0.75 + 0.25 * clamp(snoise(D * 12), -1, 1));
    }
    Ci = c;
}
