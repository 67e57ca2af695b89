// bumpmap: a dented surface, lit. The height field is a sum of two octaves of |noise| (the
// dents of the RenderMan Companion's "dented" shader, ch. 16, which the paper calls bumpmap);
// the normal comes from finite differences of the height, and a directional light shades it.
float height(float x, float y) {
    return abs(snoise(point(x * 8, y * 8, 0.5))) + 0.5 * abs(snoise(point(x * 16, y * 16, 1.5)));
}

shader bumpmap(float depth = 0.6,
               float eps = 0.01,
               color base = color(0.75, 0.72, 0.68)) {
    float h = height(u, v);
    float hx = (height(u + eps, v) - h) / eps;
    float hy = (height(u, v + eps) - h) / eps;
    vector n = normalize(vector(-0.02 * depth * hx, -0.02 * depth * hy, 1));
    vector l = normalize(vector(0.5, -0.6, 0.8));
    float diffuse = max(dot(n, l), 0);
    Ci = base * (0.15 + 0.85 * diffuse);
}
