// Menger sponge (four levels) seen from a corner: the same-picture hand-written reference for
// bench/fractal.iq, the shader bench/handwritten.sh times iqc's generated one against.
//
// Written by hand in the usual style, but every choice that decides a pixel is iqc's, so the two
// pictures agree to the bit (checked at 640x360 and 160x90):
// - camera: look-at from (2.2, 1.6, -2.6) to the origin, world up +y, focal 1/tan(30deg);
// - plain sphere tracing from where the ray enters the box, hit when |d| < 0.001, at most 200 steps (no ray of this view
//   reaches the cap, so it needs no special case); the distance is already a bound, so steps are
//   not scaled. A different march would find other hit points at the silhouettes;
// - map() does iqc's arithmetic in iqc's order (box, then s q mod 2 folded and divided by 3s), so
//   every step lands on the same float;
// - tetrahedron normal with taps 0.0005 away (half the hit tolerance), flipped to face the eye;
// - colour 0.5 + 0.5 n, background (0.05, 0.05, 0.08), exact sRGB encoding.
// For speed: the sponge lies inside the box |p| <= 1, so a ray that misses the box is background
// without marching, and a ray stops once it leaves the box (instead of running on to t = 100), as
// iqc does with the box it derives (±1.0107); a ray's march starts where it enters the box. Rays that
// can hit take exactly iqc's steps.

float map(vec3 p)
{
    // the unit box
    vec3 b = abs(p) - 1.0;
    float d = length(max(b, 0.0)) + min(max(b.x, max(b.y, b.z)), 0.0);

    // carve the crosses, three times smaller at each level
    float s = 1.0;
    for (int i = 0; i < 4; i++)
    {
        vec3 a = mod(p * s, 2.0) - 1.0;
        s *= 3.0;
        vec3 r = abs(1.0 - 3.0 * abs(a));
        float c = (min(max(r.x, r.y), min(max(r.y, r.z), max(r.z, r.x))) - 1.0) / s;
        d = max(d, c);
    }
    return d;
}

float raymarch(vec3 ro, vec3 rd)
{
    // clip to the box (a hit is within 0.001 of it; iqc's 1 + ten tolerances, rounded outward, leaves room)
    vec3 m = 1.0 / rd;
    vec3 n = m * ro;
    vec3 k = abs(m) * 1.0107422;
    vec3 t1 = -n - k;
    vec3 t2 = -n + k;
    float tN = max(max(t1.x, t1.y), t1.z);
    float tF = min(min(t2.x, t2.y), t2.z);
    if (tN > tF || tF < 0.0) return -1.0;

    // march from where the ray enters the box
    float t = max(tN, 0.0);
    for (int i = 0; i < 200; i++)
    {
        float h = map(ro + t * rd);
        if (abs(h) < 0.001) return t;
        t += h;
        if (t > tF) break;
    }
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
        n += e * map(p + 0.0005 * e);
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
    vec3 ro = vec3(2.2, 1.6, -2.6);
    vec3 ww = normalize(vec3(0.0) - ro);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    vec2 p = (2.0 * fragCoord - iResolution.xy) / iResolution.y;
    vec3 rd = normalize(mat3(uu, vv, ww) * vec3(p, 1.7320508));

    vec3 col = clamp(render(ro, rd), 0.0, 1.0);

    // linear to sRGB
    col = mix(12.92 * col, 1.055 * pow(col, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, col));
    fragColor = vec4(col, 1.0);
}
