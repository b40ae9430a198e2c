// A few shapes — same-picture reference for bench/few_shapes.iq (bench/handwritten.sh times iqc's
// generated shader against this one, and checks that both draw the same picture).
// A ball, a box turned about y and a tilted torus on a ground plane, shaded by their normals.
//
// Shared with iqc, so that the pictures agree pixel for pixel:
//  - camera: look-at from (0,2,-6) to the origin, 60 degree vertical fov (focal 1/tan(30deg)).
//  - plain sphere tracing, at most 128 steps, hit when |d| < 0.001, miss beyond t = 100. The step
//    sequence must be the same, or rays find slightly different hits at the silhouettes.
//  - out of steps, a ray still closing in on a surface within its pixel's footprint is a hit: the
//    ground near the horizon converges only geometrically and would otherwise show holes. (iqc also
//    accepts a ray stalled near a silhouette; no ray in this scene needs that, so it is left out.)
//  - tetrahedron normals with a 0.0005 offset, flipped to face the viewer.
//  - colour 0.5 + 0.5*n, background (0.05,0.05,0.08), then the exact sRGB transfer function.

float sdBox(vec3 p, vec3 b)
{
    vec3 q = abs(p) - b;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

float sdTorus(vec3 p, vec2 t)
{
    return length(vec2(length(p.xz) - t.x, p.y)) - t.y;
}

float map(vec3 p)
{
    // ground
    float d = p.y + 1.0;

    // ball at (-2,0,0), radius 1
    d = min(d, length(p - vec3(-2.0, 0.0, 0.0)) - 1.0);

    // box turned by 0.5 about y
    {
        float c = cos(0.5), s = sin(0.5);
        vec3 q = vec3(c*p.x - s*p.z, p.y, s*p.x + c*p.z);
        d = min(d, sdBox(q, vec3(0.6)));
    }

    // torus at (2,0,0), tilted by 1 about x
    {
        float c = cos(1.0), s = sin(1.0);
        vec3 q = p - vec3(2.0, 0.0, 0.0);
        q = vec3(q.x, c*q.y + s*q.z, c*q.z - s*q.y);
        d = min(d, sdTorus(q, vec2(0.8, 0.25)));
    }
    return d;
}

float raymarch(vec3 ro, vec3 rd)
{
    // nothing rises above y = 1.2411 (the torus's top plus ten tolerances, iqc's box): a ray from above
    // that level going up is background, one going down starts there
    float top = 1.2411047;
    if (ro.y > top && rd.y >= 0.0) return -1.0;
    float t = ro.y > top ? (top - ro.y) / rd.y : 0.0, tl = 0.0;    // current and last sample's distance along the ray
    float h = 1e20, hp;         // last and previous |d|
    for (int i = 0; i < 128; i++)
    {
        float d = map(ro + t*rd);
        hp = h;
        h = abs(d);
        if (h < 0.001) return t;
        tl = t;
        t += d;
        if (t > 100.0) return -1.0;
    }
    // out of steps: still closing in, and within the pixel's cone (half a pixel's angle)?
    return ((h <= hp || h < 0.01) && h < tl/(iResolution.y*1.7320508)) ? tl : -1.0;  // or within 10 tolerances
}

vec3 calcNormal(vec3 p)
{
    // tetrahedron taps; the loop keeps map() inlined only once
    vec3 n = vec3(0.0);
    for (int i = min(iFrame, 0); i < 4; i++)
    {
        vec3 e = 2.0*vec3((((i + 3) >> 1) & 1), ((i >> 1) & 1), (i & 1)) - 1.0;
        n += e*map(p + 0.0005*e);
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
    float t = raymarch(ro, rd);
    if (t < 0.0) return vec3(0.05, 0.05, 0.08);
    vec3 n = calcNormal(ro + t*rd);
    n = faceViewer(n, rd);
    return 0.5 + 0.5*n;
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    // camera
    vec3 ro = vec3(0.0, 2.0, -6.0);
    vec3 ta = vec3(0.0, 0.0, 0.0);
    vec3 ww = normalize(ta - ro);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    vec2 p = (2.0*fragCoord - iResolution.xy)/iResolution.y;
    vec3 rd = normalize(mat3(uu, vv, ww)*vec3(p, 1.7320508));

    vec3 col = clamp(render(ro, rd), 0.0, 1.0);

    // linear to sRGB
    col = mix(12.92*col, 1.055*pow(col, vec3(1.0/2.4)) - 0.055, step(0.0031308, col));
    fragColor = vec4(col, 1.0);
}
