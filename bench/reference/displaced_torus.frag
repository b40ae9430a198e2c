// Displaced torus, the scene of bench/displaced_torus.iq: a torus (R = 1, r = 0.35) plus a sine
// displacement 0.12 sin(35x) sin(35y) sin(35z). Written by hand as the same-picture reference for
// bench/handwritten.sh, which times iqc's shader for the scene against it; to be a fair baseline it
// draws the same pixels, so it makes the same algorithm choices as iqc:
//  - Lipschitz factor 8.688827, the bound iqc derives for this field's gradient (the displacement makes
//    it about 5): map() returns the field divided by it, a safe sphere-tracing step. A smaller factor
//    would be faster but a different step sequence, and so different silhouettes.
//  - hit when the field itself (the step times the factor again) is under 0.001: testing the divided
//    step instead would thicken the surface by 8.7 tolerances.
//  - sphere tracing from where the ray enters the box (below), at most 1113 steps (iqc's default cap of 128 grown by the factor
//    8.689 its steps are shortened by), far plane 100. At 128 steps, rays grazing the bumps ran out of steps (about 1,400 pixels
//    at 640x360) and many showed the background; like iqc, a ray that runs out still hits if it
//    was closing in within its pixel's cone, or came within 10 tolerances and stalled there.
//    The eye is outside the shape, so there is no inside-start case to handle.
//  - tetrahedron normals, offset 0.0005 (half the tolerance); colour 0.5 + 0.5 n (n facing the eye) on a
//    (0.05, 0.05, 0.08) background, sRGB-encoded; eye (0, 2.2, -3), 60 degree vertical field of view.
// What a hand-writer adds for speed: rays are clipped to a box around the shape (a miss is background
// without marching, a ray that leaves the box stops), as iqc clips to the box it derives; the hand box is
// the tighter one where iqc cannot see the shape's extent (through a twist it bounds only y, or takes `bound`).

#define ZERO min(iFrame, 0)

float map(vec3 p)
{
    vec2 q = vec2(length(p.xz) - 1.0, p.y);
    float d = length(q) - 0.35 + 0.12*sin(35.0*p.x)*sin(35.0*p.y)*sin(35.0*p.z);
    return d/8.688827;  // Lipschitz bound: a safe step
}

float raymarch(vec3 ro, vec3 rd)
{
    // clip to a box around the torus (radius 1, tube 0.35, displaced by up to 0.12) with room for the tolerances (iqc's: 1.48 plus
    // float rounding; the march starts where the ray enters it, so the same start gives the same steps): a ray that misses it is
    // background, one that leaves it stops
    vec3 m = 1.0/rd, n = m*ro, k = abs(m)*vec3(1.4804688, 0.48046875, 1.4804688);
    vec3 t1 = -n - k, t2 = -n + k;
    float tN = max(max(t1.x, t1.y), t1.z), tF = min(min(t2.x, t2.y), t2.z);
    if (tN > tF || tF < 0.0) return -1.0;
    float tmax = min(tF, 100.0);

    float t = max(tN, 0.0);  // from where the ray enters the box
    float dm = 1e20, tm = 0.0;  // closest approach
    float dl = 1e20, tl = 0.0;  // last sample
    float dp = 1e20;            // the one before it
    for (int i = 0; i < 1113 && t <= tmax; i++)
    {
        float h = map(ro + t*rd);
        dp = dl; dl = abs(h*8.688827); tl = t;  // the field itself
        if (dl < 0.001) break;
        if (dl < dm) { dm = dl; tm = t; }
        t += h;
    }
    if (dl < 0.001) return tl;
    if (t > tmax) return -1.0;
    // out of steps: closing in within the pixel's cone, or stalled near a silhouette
    float px = iResolution.y*1.7320508;
    if ((dl <= dp || dl < 0.01) && dl < tl/px) return tl;  // closing in, or within 10 tolerances
    if (dm < 0.01 && tl - tm <= max(0.01, tm/px)) return tm;
    return -1.0;
}

// tetrahedron normal (Quilez), one map() in a loop the compiler keeps rolled
vec3 calcNormal(vec3 p)
{
    vec3 n = vec3(0.0);
    for (int i = ZERO; i < 4; i++)
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

vec3 toSRGB(vec3 c)
{
    c = clamp(c, 0.0, 1.0);
    return mix(12.92*c, 1.055*pow(c, vec3(1.0/2.4)) - 0.055, step(0.0031308, c));
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    vec2 p = (2.0*fragCoord - iResolution.xy)/iResolution.y;

    // camera looking at the origin (world up +y), focal length 1/tan(30 deg)
    vec3 ro = vec3(0.0, 2.2, -3.0);
    vec3 ww = normalize(-ro);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    vec3 rd = normalize(mat3(uu, vv, ww)*vec3(p, 1.7320508));

    fragColor = vec4(toSRGB(render(ro, rd)), 1.0);
}
