// Sine terrain y = 0.6 sin(3x) sin(3z) at a low angle: the same-picture hand-written reference for
// bench/sine_terrain.iq, the shader bench/handwritten.sh times iqc's generated one against.
//
// Written by hand in the usual style, but every choice that decides a pixel is iqc's, so the two
// pictures agree to the bit (checked at 640x360 and 160x90):
// - camera: look-at from (0, 1.6, -4) to (0, 0, 4), world up +y, focal 1/tan(30deg);
// - p.y - h(x, z) is not a distance (its gradient reaches 2.06), so each step is divided by
//   iqc's Lipschitz factor 2.734959 while the hit test reads the undivided value: |d| < 0.001,
//   at most 351 steps (iqc's default cap of 128 grown by that factor), miss past t = 30;
// - at the step cap the far, grazing rays decide as iqc does: the last sample counts if the ray
//   was still closing in and it lies within the pixel's cone (t / (res.y * focal)), else the
//   closest sample if it came within 10 tolerances and the ray went on by no more than
//   max(10 tolerances, its cone), else background. Every part of this shows in the picture;
// - tetrahedron normal (taps 0.0005 away) of the divided field, flipped to face the eye;
// - colour 0.5 + 0.5 n, background (0.05, 0.05, 0.08), exact sRGB encoding.
// For speed: the hills stay below y = 0.6, so a ray that stays above that plus the step cap's
// tolerance up to t = 30 is background without marching (the sky and the band over the horizon, the
// costliest rays), as iqc does with the slab it derives (y <= 0.7). Rays that can hit take exactly
// iqc's steps.

float map(vec3 p)
{
    return p.y - 0.6 * sin(3.0 * p.x) * sin(3.0 * p.z);
}

float raymarch(vec3 ro, vec3 rd)
{
    // a pixel's cone radius per unit of distance
    float px = 1.0 / (iResolution.y * 1.7320508);
    // rays that never come near the hills
    if (ro.y + 30.0 * rd.y > 0.61 + 30.0 * px) return -1.0;

    // start where the ray comes down to the hills' slab (iqc's box: y <= 0.6484375, the hills plus the
    // step cap's cone at the far end)
    float t = max((0.6484375 - ro.y) / rd.y, 0.0);
    float tl = 0.0, hl = 1e20;   // last sample
    float tb = 0.0, hb = 1e20;   // closest sample
    bool closing = true;
    for (int i = 0; i < 351; i++)
    {
        float h = map(ro + t * rd);
        float a = abs(h);
        if (a < 0.001) return t;
        if (a < hb) { hb = a; tb = t; }
        closing = a <= hl;
        hl = a;
        tl = t;
        t += h / 2.734959;
        if (t > 30.0) return -1.0;
    }

    // step cap: a grazing ray still converging on the ground, or one stalled at a silhouette
    if ((closing || hl < 0.01) && hl < tl / (iResolution.y * 1.7320508)) return tl;
    if (hb < 0.01 && tl - tb <= max(0.01, tb / (iResolution.y * 1.7320508))) return tb;
    return -1.0;
}

vec3 calcNormal(vec3 p)
{
    // tetrahedron taps (1,-1,-1), (-1,-1,1), (-1,1,-1), (1,1,1); the loop keeps the compiler
    // from inlining map() four times
    vec3 n = vec3(0.0);
    for (int i = min(iFrame, 0); i < 4; i++)
    {
        vec3 e = 2.0 * vec3((((i + 3) >> 1) & 1), ((i >> 1) & 1), (i & 1)) - 1.0;
        n += e * (map(p + 0.0005 * e) / 2.734959);
    }
    return normalize(n);
}

// a normal that faces away from the ray: the hit sits just past a silhouette or a crest, where the
// surface is seen edge-on, so take it perpendicular to the ray (flipped, it would point into the surface)
vec3 faceViewer(vec3 n, vec3 rd)
{
    float c = dot(n, rd);
    if (c <= 0.0) return n;
    vec3 q = n - c*rd;
    return dot(q, q) > 1e-4 ? normalize(q) : -n;
}

vec3 render(vec3 ro, vec3 rd)
{
    vec3 col = vec3(0.05, 0.05, 0.08);
    float t = raymarch(ro, rd);
    if (t > 0.0)
    {
        vec3 n = calcNormal(ro + t * rd);
        n = faceViewer(n, rd);
        col = 0.5 + 0.5 * n;
    }
    return col;
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    // camera
    vec3 ro = vec3(0.0, 1.6, -4.0);
    vec3 ww = normalize(vec3(0.0, 0.0, 4.0) - ro);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    vec2 p = (2.0 * fragCoord - iResolution.xy) / iResolution.y;
    vec3 rd = normalize(mat3(uu, vv, ww) * vec3(p, 1.7320508));

    vec3 col = clamp(render(ro, rd), 0.0, 1.0);

    // linear to sRGB
    col = mix(12.92 * col, 1.055 * pow(col, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, col));
    fragColor = vec4(col, 1.0);
}
