// Gallery — hand-written reference for /work/main/examples/gallery.iq
// (a red ball, a fat tilted blue torus and a stretched grey box on a ground plane).
// Hand-written in the usual raymarching style: key light + soft shadows, sky/bounce fill, AO, fog, sRGB.

// ---------------------------------------------------------------- geometry

float sdSphere(vec3 p, float r) { return length(p) - r; }

float sdTorus(vec3 p, vec2 t) { return length(vec2(length(p.xz) - t.x, p.y)) - t.y; }

float sdBox(vec3 p, vec3 b)
{
    vec3 q = abs(p) - b;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

// returns (distance, material id)
vec2 map(vec3 p)
{
    // ball: T(-2,0,2), r = 0.8
    vec2 res = vec2(sdSphere(p - vec3(-2.0, 0.0, 2.0), 0.8), 1.0);

    // ring: T(0,0,3) * Rx(1.2), radii (0.77, 0.6)
    {
        vec3 q = p - vec3(0.0, 0.0, 3.0);
        float c = cos(1.2), s = sin(1.2);
        q = vec3(q.x, c*q.y + s*q.z, -s*q.y + c*q.z);   // inverse of Rx
        float d = sdTorus(q, vec2(0.77, 0.6));
        if (d < res.x) res = vec2(d, 2.0);
    }

    // box: T(2,0,2) * Ry(0.6) * S(1,1.5,1) of a 0.5 half-size cube = half sizes (0.5,0.75,0.5)
    {
        vec3 q = p - vec3(2.0, 0.0, 2.0);
        float c = cos(0.6), s = sin(0.6);
        q = vec3(c*q.x - s*q.z, q.y, s*q.x + c*q.z);    // inverse of Ry
        float d = sdBox(q, vec3(0.5, 0.75, 0.5));
        if (d < res.x) res = vec2(d, 3.0);
    }

    // ground: y = -1
    {
        float d = p.y + 1.0;
        if (d < res.x) res = vec2(d, 4.0);
    }
    return res;
}

vec3 calcNormal(vec3 p)
{
    const vec2 e = vec2(1.0, -1.0) * 0.0005;
    return normalize(e.xyy*map(p + e.xyy).x + e.yyx*map(p + e.yyx).x +
                     e.yxy*map(p + e.yxy).x + e.xxx*map(p + e.xxx).x);
}

vec2 raycast(vec3 ro, vec3 rd)
{
    float t = 0.0;
    for (int i = 0; i < 160; i++)
    {
        vec2 h = map(ro + rd*t);
        if (abs(h.x) < 0.0005*t) return vec2(t, h.y);
        t += h.x;
        if (t > 60.0) break;
    }
    return vec2(-1.0);
}

float calcSoftshadow(vec3 ro, vec3 rd, float tmin, float tmax, float k)
{
    float res = 1.0;
    float t = tmin;
    float ph = 1e10;
    for (int i = 0; i < 64; i++)
    {
        float h = map(ro + rd*t).x;
        float y = h*h/(2.0*ph);
        float d = sqrt(max(h*h - y*y, 0.0));
        res = min(res, k*d/max(0.0, t - y));
        ph = h;
        t += clamp(h, 0.01, 0.25);
        if (res < 0.001 || t > tmax) break;
    }
    res = clamp(res, 0.0, 1.0);
    return res*res*(3.0 - 2.0*res);
}

float calcAO(vec3 pos, vec3 nor)
{
    float occ = 0.0;
    float sca = 1.0;
    for (int i = 0; i < 5; i++)
    {
        float h = 0.02 + 0.15*float(i);
        float d = map(pos + h*nor).x;
        occ += (h - d)*sca;
        sca *= 0.85;
    }
    return clamp(1.0 - 1.6*occ, 0.0, 1.0);
}

// ---------------------------------------------------------------- shading

const vec3 BACKGROUND = vec3(0.0063, 0.0094, 0.018);
const vec3 LIGHT_POS  = vec3(3.0, 6.0, -4.0);

vec3 skyColor(vec3 rd)
{
    // a dark night-blue dome, a touch lighter toward the horizon
    float h = clamp(rd.y, 0.0, 1.0);
    return mix(vec3(0.030, 0.036, 0.055), BACKGROUND, pow(h, 0.5));
}

vec3 render(vec3 ro, vec3 rd)
{
    vec3 col = skyColor(rd);
    vec2 res = raycast(ro, rd);
    if (res.x < 0.0) return col;

    float t = res.x;
    float m = res.y;
    vec3 pos = ro + rd*t;
    vec3 nor = (m > 3.5) ? vec3(0.0, 1.0, 0.0) : calcNormal(pos);
    vec3 ref = reflect(rd, nor);

    // materials (lambert k_d from the scene; the ground, unlit in the file, gets a soft sage floor)
    vec3 alb;
    float spe = 0.0;
    if (m < 1.5)      { alb = vec3(0.793, 0.071, 0.029); spe = 0.25; }
    else if (m < 2.5) { alb = vec3(0.029, 0.325, 0.793); spe = 0.25; }
    else if (m < 3.5) { alb = vec3(0.612);                spe = 0.15; }
    else
    {
        alb = vec3(0.26, 0.34, 0.27);
        // very faint large-scale variation so the floor doesn't look like CG plastic
        float f = 0.5 + 0.5*sin(pos.x*1.3 + sin(pos.z*0.9))*sin(pos.z*1.1 + 1.7);
        alb *= 0.92 + 0.08*f;
        spe = 0.05;
    }

    float occ = calcAO(pos, nor);

    // key light (point at LIGHT_POS, warm)
    vec3  toL = LIGHT_POS - pos;
    float dL  = length(toL);
    vec3  lig = toL/dL;
    float dif = clamp(dot(nor, lig), 0.0, 1.0);
    if (dif > 0.001) dif *= calcSoftshadow(pos + nor*0.002, lig, 0.02, dL, 12.0);
    vec3  hal = normalize(lig - rd);
    float spc = pow(clamp(dot(nor, hal), 0.0, 1.0), 24.0) * dif *
                (0.04 + 0.96*pow(clamp(1.0 - dot(hal, lig), 0.0, 1.0), 5.0));

    // sky (hemisphere) fill
    float sky = sqrt(clamp(0.5 + 0.5*nor.y, 0.0, 1.0)) * occ;
    // back / rim light, opposite the key
    vec3  bl  = normalize(vec3(-lig.x, 0.0, -lig.z));
    float bac = clamp(dot(nor, bl), 0.0, 1.0) * clamp(1.0 - pos.y*0.5, 0.0, 1.0) * occ;
    // bounce from the floor
    float bou = clamp(-nor.y, 0.0, 1.0) * occ;
    // cool fill from the front-left, unshadowed
    float fil = clamp(dot(nor, normalize(vec3(-0.8, 0.35, -0.5))), 0.0, 1.0) * occ;
    // fresnel rim
    float fre = pow(clamp(1.0 + dot(nor, rd), 0.0, 1.0), 2.0) * occ;

    vec3 lin = vec3(0.0);
    lin += 1.5*dif*vec3(1.25, 1.02, 0.80);
    lin += 0.40*sky*vec3(0.30, 0.40, 0.75);
    lin += 0.35*bac*vec3(0.25, 0.25, 0.30);
    lin += 0.40*bou*vec3(0.25, 0.35, 0.25);
    lin += 0.22*fil*vec3(0.45, 0.55, 0.85);
    lin += 0.25*fre*vec3(0.60, 0.70, 0.90);
    col = alb*lin;
    col += spe*spc*vec3(1.25, 1.02, 0.80)*4.0;

    // a soft pool of light on the stage; the floor falls off into the night
    float pool = exp(-0.02*dot(pos.xz - vec2(0.0, 2.5), pos.xz - vec2(0.0, 2.5)));
    col *= mix(0.15, 1.0, pool);

    // fog toward the background
    col = mix(col, skyColor(rd), 1.0 - exp(-0.0025*t*t));
    return col;
}

mat3 setCamera(vec3 ro, vec3 ta)
{
    vec3 fw = normalize(ta - ro);
    vec3 rt = normalize(cross(vec3(0.0, 1.0, 0.0), fw));
    vec3 up = cross(fw, rt);
    return mat3(rt, up, fw);
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    vec3 ro = vec3(0.0, 2.0, -4.0);
    vec3 ta = vec3(0.0, 0.0, 2.0);
    mat3 ca = setCamera(ro, ta);
    float fl = 1.0/tan(radians(55.0)*0.5);

    vec3 tot = vec3(0.0);
    // 2x2 supersampling
    for (int j = 0; j < 2; j++)
    for (int i = 0; i < 2; i++)
    {
        vec2 o = vec2(float(i), float(j))/2.0 - 0.25;
        vec2 uv = (2.0*(fragCoord + o) - iResolution.xy)/iResolution.y;
        vec3 rd = normalize(ca*vec3(uv, fl));
        vec3 col = render(ro, rd);
        // gentle filmic-ish shoulder, then sRGB
        col = col/(1.0 + 0.25*col);
        col = mix(12.92*col, 1.055*pow(col, vec3(1.0/2.4)) - 0.055, step(0.0031308, col));
        tot += col;
    }
    tot /= 4.0;

    // vignette
    vec2 q = fragCoord/iResolution.xy;
    tot *= 0.6 + 0.4*pow(16.0*q.x*q.y*(1.0 - q.x)*(1.0 - q.y), 0.15);

    fragColor = vec4(clamp(tot, 0.0, 1.0), 1.0);
}
