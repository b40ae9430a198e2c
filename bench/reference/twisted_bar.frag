// Twisted bar, the scene of bench/twisted_bar.iq: a 0.6 x 3 x 0.6 bar twisted about its long axis (y)
// by 2.2 radians per unit of height. Written by hand as the same-picture reference for
// bench/handwritten.sh, which times iqc's shader for the scene against it; to be a fair baseline it
// draws the same pixels, so it makes the same algorithm choices as iqc:
//  - Lipschitz factor 5.673572, the bound iqc derives for the twisted field's gradient: map() returns
//    the bar's distance divided by it, a safe sphere-tracing step. The true bound is about 1.3 and
//    would be much faster, but it is a different step sequence and so different silhouettes.
//  - the scene's bounding sphere, radius 1.6: more than 0.1 outside it map() returns the (exact,
//    undivided) distance to the sphere, as iqc does. It is a select, not a branch: llvmpipe runs
//    both sides of an `if` anyway.
//  - hit when the field itself (the step times the factor again) is under 0.001: testing the divided
//    step instead would thicken the surface by 5.7 tolerances.
//  - sphere tracing from where the ray enters the box (below), at most 727 steps (iqc's default cap of 128 grown by the factor
//    5.67 its steps are shortened by), far plane 100. Some rays grazing the twisted edges
//    run out of steps; like iqc, such a ray still hits if it was closing in within its pixel's cone, or
//    came within 10 tolerances and stalled there. The eye is outside the shape, so there is no
//    inside-start case to handle.
//  - tetrahedron normals, offset 0.0005 (half the tolerance); colour 0.5 + 0.5 n (n facing the eye) on a
//    (0.05, 0.05, 0.08) background, sRGB-encoded; eye (0, 0.5, -4), 60 degree vertical field of view.
// What a hand-writer adds for speed: rays are clipped to a box around the shape (a miss is background
// without marching, a ray that leaves the box stops), as iqc clips to the box it derives; the hand box is
// the tighter one where iqc cannot see the shape's extent (through a twist it bounds only y, or takes `bound`).

#define ZERO min(iFrame, 0)

float sdBox(vec3 p, vec3 b)
{
    vec3 q = abs(p) - b;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

float map(vec3 p)
{
    float bound = length(p) - 1.6;
    // twist about y
    float c = cos(2.2*p.y);
    float s = sin(2.2*p.y);
    vec3 q = vec3(c*p.x - s*p.z, p.y, s*p.x + c*p.z);
    float d = sdBox(q, vec3(0.3, 1.5, 0.3))/5.673572;  // Lipschitz bound: a safe step
    return bound > 0.1 ? bound : d;
}

float raymarch(vec3 ro, vec3 rd)
{
    // clip to a box around the twisted bar (half-extents 0.3, 1.5, 0.3: within 0.43 of the y axis) with room for the tolerances: a ray that misses it is background, one that leaves it stops
    vec3 m = 1.0/rd, n = m*ro, k = abs(m)*vec3(0.4348941, 1.5107422, 0.4348941);
    vec3 t1 = -n - k, t2 = -n + k;
    float tN = max(max(t1.x, t1.y), t1.z), tF = min(min(t2.x, t2.y), t2.z);
    if (tN > tF || tF < 0.0) return -1.0;
    float tmax = min(tF, 100.0);

    float t = max(tN, 0.0);  // from where the ray enters the box
    float dm = 1e20, tm = 0.0;  // closest approach
    float dl = 1e20, tl = 0.0;  // last sample
    float dp = 1e20;            // the one before it
    for (int i = 0; i < 727 && t <= tmax; i++)
    {
        float h = map(ro + t*rd);
        dp = dl; dl = abs(h*5.673572); tl = t;  // the field itself
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
    vec3 ro = vec3(0.0, 0.5, -4.0);
    vec3 ww = normalize(-ro);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    vec3 rd = normalize(mat3(uu, vv, ww)*vec3(p, 1.7320508));

    fragColor = vec4(toSRGB(render(ro, rd)), 1.0);
}
