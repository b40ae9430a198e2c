// Grazing plane, thin features — same-picture reference for bench/grazing_thin.iq (bench/handwritten.sh
// times iqc's generated shader against this one, and checks that both draw the same picture).
// A camera 5 cm above a ground plane looking along it, two thin plates and a thin rod: rays that run
// close to a surface for a long way, so many of them use up their steps.
//
// Shared with iqc, so that the pictures agree pixel for pixel:
//  - camera: look-at from (0,-0.45,-6) to (0,-0.5,10), 60 degree vertical fov (focal 1/tan(30deg)).
//  - plain sphere tracing, at most 128 steps, hit when |d| < 0.001, miss beyond t = 60. The step
//    sequence must be the same, or rays find slightly different hits along the thin edges.
//  - out of steps (about 6% of the pixels here), a ray is still a hit if
//      it is still closing in on a surface within its pixel's cone (the ground towards the horizon), or
//      it came within 0.01 of a surface and has moved on by no more than max(0.01, the cone) since
//      (a ray stalled along a plate's edge);
//    else it is a miss.
//  - tetrahedron normals with a 0.0005 offset.
//  - colour 0.5 + 0.5*n, background (0.05,0.05,0.08), then the exact sRGB transfer function.

float sdBox(vec3 p, vec3 b)
{
    vec3 q = abs(p) - b;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

float map(vec3 p)
{
    // ground
    float d = p.y + 0.5;

    // plate at (0,0.5,4), tilted by 0.2 about x
    {
        float c = cos(0.2), s = sin(0.2);
        vec3 q = p - vec3(0.0, 0.5, 4.0);
        q = vec3(q.x, c*q.y + s*q.z, c*q.z - s*q.y);
        d = min(d, sdBox(q, vec3(2.0, 0.01, 2.0)));
    }

    // plate at (-3,0,8), turned by 1.4 about z: nearly upright
    {
        float c = cos(1.4), s = sin(1.4);
        vec3 q = p - vec3(-3.0, 0.0, 8.0);
        q = vec3(c*q.x + s*q.y, c*q.y - s*q.x, q.z);
        d = min(d, sdBox(q, vec3(1.5, 0.005, 3.0)));
    }

    // vertical rod through (1.5,0,2), radius 0.01
    d = min(d, length(p.xz - vec2(1.5, 2.0)) - 0.01);
    return d;
}

float raymarch(vec3 ro, vec3 rd)
{
    float t = 0.0, tl = 0.0;    // current and last sample's distance along the ray
    float h = 1e20, hp;         // last and previous |d|
    float hm = 1e20, tm = 0.0;  // closest approach, and where
    for (int i = 0; i < 128; i++)
    {
        float d = map(ro + t*rd);
        hp = h;
        h = abs(d);
        if (h < 0.001) return t;
        if (h < hm) { hm = h; tm = t; }
        tl = t;
        t += d;
        if (t > 60.0) return -1.0;
    }
    // out of steps
    float cone = 1.0/(iResolution.y*1.7320508);     // half a pixel's angle
    if ((h <= hp || h < 0.01) && h < tl*cone) return tl;  // converging, or within 10 tolerances, in the pixel
    if (hm < 0.01 && tl - tm <= max(0.01, tm*cone)) return tm;  // stalled near an edge
    return -1.0;
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

vec3 render(vec3 ro, vec3 rd)
{
    float t = raymarch(ro, rd);
    if (t < 0.0) return vec3(0.05, 0.05, 0.08);
    return 0.5 + 0.5*calcNormal(ro + t*rd);
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    // camera
    vec3 ro = vec3(0.0, -0.45, -6.0);
    vec3 ta = vec3(0.0, -0.5, 10.0);
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
