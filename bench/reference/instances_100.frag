// 100 instances — same-picture reference for bench/instances_100.iq (bench/handwritten.sh times iqc's
// generated shader against this one, and checks that both draw the same picture).
// A 10x10 grid of small tori (radii 0.3, 0.1) one unit apart in the z = 0 plane; torus k = 10*row + col
// sits at (col - 4.5, row - 4.5, 0) and is tilted about x by 0.4*(k mod 7).
//
// Shared with iqc, so that the pictures agree pixel for pixel:
//  - camera: look-at from (0,0,-14) to the origin, 60 degree vertical fov (focal 1/tan(30deg)).
//  - plain sphere tracing from where the ray enters the grid's bounding box, at most 128 steps, hit
//    when |d| < 0.001, miss beyond t = 100. map() returns the exact union distance (the min over all
//    100 tori, equal up to rounding), so the step sequence is the same: a cheaper bound would find
//    slightly different hits at the silhouettes.
//    No ray here runs out of steps.
//  - tetrahedron normals with a 0.0005 offset.
//  - colour 0.5 + 0.5*n, background (0.05,0.05,0.08), then the exact sRGB transfer function.
// What is done differently, for speed: each torus fits in a ball of radius 0.4 around its cell's centre,
// so map() only visits the cells that can hold the nearest torus. Like iqc: rays that miss the grid's
// bounding box are background without marching, a ray stops once it leaves the box, and the normal taps
// evaluate only the torus the ray hit.

// the seven tilts 0.4*m, m = 0..6, as (cos, sin): folded at compile time, cheaper than cos() and sin()
// per torus
const vec2 tilt[7] = vec2[7](vec2(cos(0.0), sin(0.0)), vec2(cos(0.4), sin(0.4)), vec2(cos(0.8), sin(0.8)),
                             vec2(cos(1.2), sin(1.2)), vec2(cos(1.6), sin(1.6)), vec2(cos(2.0), sin(2.0)),
                             vec2(cos(2.4), sin(2.4)));

// torus of cell (i,j) at p
float sdCell(vec3 p, int i, int j)
{
    vec2 cs = tilt[(10*j + i) % 7];
    vec3 q = p - vec3(float(i) - 4.5, float(j) - 4.5, 0.0);
    q = vec3(q.x, cs.x*q.y + cs.y*q.z, cs.x*q.z - cs.y*q.y);
    return length(vec2(length(q.xz) - 0.3, q.y)) - 0.1;
}

float map(vec3 p)
{
    // nearest cell first: an upper bound on the distance
    ivec2 c0 = ivec2(clamp(floor(p.xy + 5.0), 0.0, 9.0));
    float d = sdCell(p, c0.x, c0.y);

    // a torus is no nearer than its centre minus 0.4, so only cells whose centre lies within r (in xy)
    // of p can beat d (with 0.001 to spare for rounding)
    float r = sqrt(max((d + 0.401)*(d + 0.401) - p.z*p.z, 0.0));
    ivec2 lo = ivec2(max(ceil(p.xy - r + 4.5), 0.0));
    ivec2 hi = ivec2(min(floor(p.xy + r + 4.5), 9.0));
    for (int j = lo.y; j <= hi.y; j++)
    for (int i = lo.x; i <= hi.x; i++)
        d = min(d, sdCell(p, i, j));
    return d;
}

// the grid's bounding box, |x|,|y| < 4.9, |z| < 0.4, grown by a bit: entry and exit distances
vec2 iBox(vec3 ro, vec3 rd)
{
    vec3 m = 1.0/rd;
    vec3 n = m*ro;
    vec3 k = abs(m)*vec3(4.91, 4.91, 0.41);
    vec3 t1 = -n - k, t2 = -n + k;
    return vec2(max(max(t1.x, t1.y), t1.z), min(min(t2.x, t2.y), t2.z));
}

float raymarch(vec3 ro, vec3 rd)
{
    vec2 b = iBox(ro, rd);
    if (b.x > b.y) return -1.0;
    float tmax = min(b.y, 100.0);
    float t = max(b.x, 0.0);  // from where the ray enters the box
    for (int i = 0; i < 128; i++)
    {
        float d = map(ro + t*rd);
        if (abs(d) < 0.001) return t;
        t += d;
        if (t > tmax) break;
    }
    return -1.0;
}

vec3 calcNormal(vec3 p)
{
    // only the torus that was hit: its cell contains p
    ivec2 c = ivec2(floor(p.xy + 5.0));
    vec3 n = vec3(0.0);
    for (int i = min(iFrame, 0); i < 4; i++)
    {
        vec3 e = 2.0*vec3((((i + 3) >> 1) & 1), ((i >> 1) & 1), (i & 1)) - 1.0;
        n += e*sdCell(p + 0.0005*e, c.x, c.y);
    }
    return normalize(n);
}

vec3 render(vec3 ro, vec3 rd)
{
    float t = raymarch(ro, rd);
    if (t < 0.0) return vec3(0.05, 0.05, 0.08);
    return 0.5 + 0.5*calcNormal(ro + t*rd);
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    // camera
    vec3 ro = vec3(0.0, 0.0, -14.0);
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
