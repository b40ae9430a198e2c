// Hand-written reference for examples/menger.iq: a 4-iteration Menger sponge (rotated 0.4 rad about y)
// on a checkered floor. Written by hand in the usual raymarching style (not compiler output):
// key light with soft shadows, sky dome fill, bounce from the floor, AO, fog, filtered checkers, sRGB.

#define AA 2

const vec3  CAM_POS  = vec3(2.6, 2.1, -3.4);
const vec3  CAM_TGT  = vec3(0.0, -0.15, 0.0);
const float FOV      = 50.0;
const vec3  LIGHT_P  = vec3(4.0, 6.0, -2.5);
const vec3  LIGHT_C  = vec3(1.0, 0.95, 0.85);
const vec3  ZENITH   = vec3(0.18, 0.30, 0.55);
const vec3  HORIZON  = vec3(0.60, 0.68, 0.80);
const vec3  SPONGE_C = vec3(0.699, 0.268, 0.047);
const vec3  CHECK_1  = vec3(0.612, 0.612, 0.612);
const vec3  CHECK_2  = vec3(0.173, 0.173, 0.218);
const float CHECK_S  = 0.5;

//------------------------------------------------------------------ geometry

float sdBox(vec3 p, vec3 b)
{
    vec3 d = abs(p) - b;
    return min(max(d.x, max(d.y, d.z)), 0.0) + length(max(d, 0.0));
}

// Menger sponge of half size 1, 4 iterations; .y returns a cavity measure used for occlusion tint
vec2 sdMenger(vec3 p)
{
    float d = sdBox(p, vec3(1.0));
    float s = 1.0;
    float trap = 1.0;
    for (int i = 0; i < 4; i++)
    {
        vec3 a = mod(p * s, 2.0) - 1.0;
        s *= 3.0;
        vec3 r = abs(1.0 - 3.0 * abs(a));
        float da = max(r.x, r.y);
        float db = max(r.y, r.z);
        float dc = max(r.z, r.x);
        float c = (min(da, min(db, dc)) - 1.0) / s;
        if (c > d) { d = c; trap = min(trap, 0.25 + 0.75 * float(i) / 3.0); }
    }
    return vec2(d, trap);
}

vec3 toSponge(vec3 p)
{
    // world -> object: inverse of R_y(0.4)
    const float c = 0.92106099, s = 0.38941834;
    return vec3(c * p.x - s * p.z, p.y, s * p.x + c * p.z);
}

// x: distance, y: material id (1 floor, 2 sponge), z: sponge trap
vec3 map(vec3 p)
{
    vec3 res = vec3(p.y + 1.0, 1.0, 1.0);
    vec2 m = sdMenger(toSponge(p));
    if (m.x < res.x) res = vec3(m.x, 2.0, m.y);
    return res;
}

float mapD(vec3 p) { return min(p.y + 1.0, sdMenger(toSponge(p)).x); }

vec3 calcNormal(vec3 p, float t)
{
    vec2 e = vec2(1.0, -1.0) * 0.0004 * max(1.0, t);
    return normalize(e.xyy * mapD(p + e.xyy) + e.yyx * mapD(p + e.yyx) +
                     e.yxy * mapD(p + e.yxy) + e.xxx * mapD(p + e.xxx));
}

vec3 raymarch(vec3 ro, vec3 rd)
{
    float tmax = 30.0;
    // the floor analytically bounds the march
    if (rd.y < 0.0) tmax = min(tmax, (-1.0 - ro.y) / rd.y);
    vec3 res = vec3(-1.0);
    float t = 0.01;
    for (int i = 0; i < 160 && t < tmax; i++)
    {
        vec3 h = map(ro + rd * t);
        if (abs(h.x) < 0.0002 * t) { res = vec3(t, h.yz); break; }
        t += h.x;
    }
    if (res.x < 0.0 && rd.y < 0.0 && tmax < 30.0) res = vec3(tmax, 1.0, 1.0);
    return res;
}

float softShadow(vec3 ro, vec3 rd, float tmax, float k)
{
    float res = 1.0;
    float t = 0.005;
    float ph = 1e10;
    for (int i = 0; i < 64; i++)
    {
        float h = mapD(ro + rd * t);
        float y = h * h / (2.0 * ph);
        float d = sqrt(max(h * h - y * y, 0.0));
        res = min(res, k * d / max(0.0, t - y));
        ph = h;
        t += clamp(h, 0.005, 0.15);
        if (res < 0.001 || t > tmax) break;
    }
    res = clamp(res, 0.0, 1.0);
    return res * res * (3.0 - 2.0 * res);
}

float calcAO(vec3 p, vec3 n)
{
    float occ = 0.0;
    float sca = 1.0;
    for (int i = 0; i < 6; i++)
    {
        float h = 0.005 + 0.16 * float(i) / 5.0;
        float d = mapD(p + h * n);
        occ += (h - d) * sca;
        sca *= 0.85;
    }
    return clamp(1.0 - 2.2 * occ, 0.0, 1.0);
}

//------------------------------------------------------------------ shading

vec3 skyColor(vec3 rd)
{
    float y = max(rd.y, 0.0);
    vec3 col = mix(HORIZON, ZENITH, pow(y, 0.6));
    vec3 ld = normalize(LIGHT_P);
    col += LIGHT_C * 0.25 * pow(max(dot(rd, ld), 0.0), 8.0);
    return col;
}

// box-filtered checkerboard (Quilez, "filtering procedurals")
float checkers(vec2 p, vec2 w)
{
    w = max(w, 0.0001);
    vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
    return 0.5 - 0.5 * i.x * i.y;
}

vec3 render(vec3 ro, vec3 rd, vec3 rdx, vec3 rdy)
{
    vec3 col = skyColor(rd);
    vec3 res = raymarch(ro, rd);
    float t = res.x;
    if (t > 0.0)
    {
        vec3 pos = ro + t * rd;
        vec3 nor = (res.y < 1.5) ? vec3(0.0, 1.0, 0.0) : calcNormal(pos, t);
        vec3 ref = reflect(rd, nor);

        vec3 alb;
        float spe;
        float shin;
        if (res.y < 1.5)
        {
            // floor: ray differentials give the pixel footprint on the plane
            vec3 dpdx = (-1.0 - ro.y) * (rdx / rdx.y - rd / rd.y);
            vec3 dpdy = (-1.0 - ro.y) * (rdy / rdy.y - rd / rd.y);
            vec2 q = pos.xz / CHECK_S;
            vec2 w = (abs(dpdx.xz) + abs(dpdy.xz)) / CHECK_S;
            // the scene's 3D checker includes floor(y/s) = -3 on this floor: c_1 sits on odd xz cells
            float f = checkers(q + vec2(1.0, 0.0), w);
            alb = mix(CHECK_1, CHECK_2, f);
            spe = 0.04;
            shin = 16.0;
        }
        else
        {
            alb = SPONGE_C;
            spe = 0.25;
            shin = 24.0;
        }

        vec3 lvec = LIGHT_P - pos;
        float ldis = length(lvec);
        vec3 lig = lvec / ldis;
        vec3 hal = normalize(lig - rd);

        float occ = calcAO(pos, nor);
        if (res.y > 1.5) occ *= mix(0.55, 1.0, res.z);

        float dif = clamp(dot(nor, lig), 0.0, 1.0);
        if (dif > 0.0001) dif *= softShadow(pos + nor * 0.002, lig, ldis, 12.0);
        float sky = sqrt(clamp(0.5 + 0.5 * nor.y, 0.0, 1.0));
        float bou = clamp(0.3 - 0.7 * nor.y, 0.0, 1.0) * clamp(1.0 - (pos.y + 1.0) * 0.5, 0.0, 1.0);
        float bac = clamp(dot(nor, normalize(vec3(-lig.x, 0.0, -lig.z))), 0.0, 1.0);
        float fre = pow(clamp(1.0 + dot(nor, rd), 0.0, 1.0), 5.0);
        float sp = pow(clamp(dot(nor, hal), 0.0, 1.0), shin) * dif * (0.04 + 0.96 * fre) * spe * 8.0;

        vec3 lin = vec3(0.0);
        lin += 1.5 * dif * LIGHT_C;
        lin += 0.30 * sky * vec3(0.55, 0.68, 0.95) * occ;
        lin += 0.25 * bou * vec3(0.45, 0.40, 0.35) * occ;
        lin += 0.10 * bac * vec3(0.35, 0.30, 0.25) * occ;
        lin += 0.10 * fre * vec3(1.0) * occ * (0.5 + 0.5 * dif);
        col = alb * lin;
        col += sp * LIGHT_C;
        // sky reflected on the floor at grazing angles
        if (res.y < 1.5) col += 0.15 * fre * skyColor(ref) * occ;

        // fog towards the horizon colour
        col = mix(col, HORIZON * 0.95, 1.0 - exp(-0.0025 * t * t));
    }
    return col;
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    vec3 ww = normalize(CAM_TGT - CAM_POS);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    float fl = 1.0 / tan(radians(FOV) * 0.5);

    vec3 tot = vec3(0.0);
    for (int m = 0; m < AA; m++)
    for (int n = 0; n < AA; n++)
    {
        vec2 o = vec2(float(m), float(n)) / float(AA) - 0.5 + 0.5 / float(AA);
        vec2 p  = (2.0 * (fragCoord + o) - iResolution.xy) / iResolution.y;
        vec2 px = (2.0 * (fragCoord + o + vec2(1.0, 0.0)) - iResolution.xy) / iResolution.y;
        vec2 py = (2.0 * (fragCoord + o + vec2(0.0, 1.0)) - iResolution.xy) / iResolution.y;
        mat3 ca = mat3(uu, vv, ww);
        vec3 rd  = normalize(ca * vec3(p, fl));
        vec3 rdx = normalize(ca * vec3(px, fl));
        vec3 rdy = normalize(ca * vec3(py, fl));

        vec3 col = render(CAM_POS, rd, rdx, rdy);
        // gentle filmic shoulder, then sRGB
        col = col / (1.0 + 0.15 * col);
        col = pow(clamp(col, 0.0, 1.0), vec3(0.4545));
        tot += col;
    }
    tot /= float(AA * AA);

    // light contrast curve and vignette
    tot = tot * 0.6 + 0.4 * tot * tot * (3.0 - 2.0 * tot);
    vec2 q = fragCoord / iResolution.xy;
    tot *= 0.6 + 0.4 * pow(16.0 * q.x * q.y * (1.0 - q.x) * (1.0 - q.y), 0.12);

    fragColor = vec4(tot, 1.0);
}
