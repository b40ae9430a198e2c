// Hand-written reference for examples/glass_and_mirror.iq: a glass ball and a mirror ball on a red and white
// checkered floor. Written by hand (not compiler output): point key light with soft shadows, sky and bounce
// fill, analytic sphere AO, 2 bounces of reflection/refraction, a glass caustic, filtered checkers, fog, sRGB.

#define AA 2

const vec3  CAM_POS = vec3(0.0, 1.4, -4.5);
const vec3  CAM_TGT = vec3(0.0, -0.2, 0.5);
const float FOV     = 50.0;

const vec3  LIGHT_P = vec3(-3.0, 6.0, -4.0);
const vec3  LIGHT_C = vec3(1.0, 0.97, 0.92);
const vec3  SKY_COL = vec3(0.17, 0.24, 0.38);
const vec3  BOU_COL = vec3(0.22, 0.12, 0.10);      // warm-red bounce from the checkers
const vec3  ZENITH  = vec3(0.15, 0.28, 0.60);
const vec3  HORIZON = vec3(0.55, 0.65, 0.80);

const vec4  SPH_GLASS  = vec4(-1.1, 0.0, 0.0, 1.0);
const vec4  SPH_MIRROR = vec4( 1.2, 0.0, 1.0, 1.0);
const vec3  GLASS_KT   = vec3(0.9, 0.95, 0.92);
const float GLASS_ETA  = 1.5;
const float GLASS_KR   = 0.1;
const float MIRROR_KR  = 0.9;
const vec3  MIRROR_KD  = vec3(0.05);

const vec3  CHECK_1 = vec3(0.793, 0.793, 0.793);
const vec3  CHECK_2 = vec3(0.456, 0.015, 0.009);
const float CHECK_S = 0.75;

#define MAT_FLOOR  1.0
#define MAT_MIRROR 2.0
#define MAT_GLASS  3.0

//------------------------------------------------------------------ scene

float sdSphere(vec3 p, vec4 s) { return length(p - s.xyz) - s.w; }

vec2 opU(vec2 a, vec2 b) { return (a.x < b.x) ? a : b; }

vec2 map(vec3 p)
{
    vec2 res = vec2(p.y + 1.0, MAT_FLOOR);
    res = opU(res, vec2(sdSphere(p, SPH_MIRROR), MAT_MIRROR));
    res = opU(res, vec2(sdSphere(p, SPH_GLASS),  MAT_GLASS));
    return res;
}

float mapOpaque(vec3 p) { return min(p.y + 1.0, sdSphere(p, SPH_MIRROR)); }

vec3 calcNormal(vec3 p)
{
    vec2 e = vec2(1.0, -1.0) * 0.0005;
    return normalize(e.xyy * map(p + e.xyy).x + e.yyx * map(p + e.yyx).x +
                     e.yxy * map(p + e.yxy).x + e.xxx * map(p + e.xxx).x);
}

vec2 raymarch(vec3 ro, vec3 rd)
{
    float t = 0.0;
    for (int i = 0; i < 128; i++)
    {
        vec2 h = map(ro + rd * t);
        if (abs(h.x) < 0.0001 * (1.0 + t)) return vec2(t, h.y);
        t += h.x;
        if (t > 40.0) break;
    }
    return vec2(-1.0);
}

float softShadow(vec3 ro, vec3 rd, float tmax, float k)
{
    float res = 1.0;
    float t = 0.01;
    for (int i = 0; i < 64; i++)
    {
        float h = mapOpaque(ro + rd * t);
        res = min(res, k * h / t);
        t += clamp(h, 0.01, 0.3);
        if (res < 0.001 || t > tmax) break;
    }
    res = clamp(res, 0.0, 1.0);
    return res * res * (3.0 - 2.0 * res);
}

// The glass ball between a point and the light: a dim tinted shadow with the ball lens' caustic inside.
vec3 glassShadow(vec3 p, vec3 lig)
{
    vec3  c = SPH_GLASS.xyz - p;
    float r = SPH_GLASS.w;
    float s = dot(c, lig);
    if (s < 0.0) return vec3(1.0);
    float d = length(c - lig * s);
    float inside = 1.0 - smoothstep(0.92 * r, 1.04 * r, d);
    float f = GLASS_ETA * r / (2.0 * (GLASS_ETA - 1.0));   // paraxial focus, from the centre
    float w = r * max(abs(s - f) / f, 0.22);
    float caus = min(r * r / (w * w), 6.0) * exp(-d * d / (w * w));
    vec3  trans = GLASS_KT * GLASS_KT * (0.10 + 0.8 * caus);
    return mix(vec3(1.0), trans, inside);
}

float sphOcclusion(vec3 pos, vec3 nor, vec4 sph)
{
    vec3  di = sph.xyz - pos;
    float l  = length(di);
    float h  = l / sph.w;
    return clamp(dot(nor, di / l), 0.0, 1.0) / (h * h);
}

float calcAO(vec3 pos, vec3 nor)
{
    float occ = (1.0 - sphOcclusion(pos, nor, SPH_MIRROR)) * (1.0 - 0.5 * sphOcclusion(pos, nor, SPH_GLASS));
    occ *= clamp(0.5 + 0.5 * nor.y + 0.5 * (pos.y + 1.0), 0.0, 1.0);
    return clamp(occ, 0.0, 1.0);
}

//------------------------------------------------------------------ materials and lighting

vec3 skyColor(vec3 rd)
{
    float y = max(rd.y, 0.0);
    vec3 col = mix(HORIZON, ZENITH, pow(y, 0.45));
    col = mix(col, HORIZON * 0.85, smoothstep(0.0, -0.3, rd.y));
    vec3 ld = normalize(LIGHT_P);
    float sun = clamp(dot(rd, ld), 0.0, 1.0);
    col += LIGHT_C * (0.2 * pow(sun, 10.0) + 4.0 * pow(sun, 900.0));
    return col;
}

// box-filtered checkerboard (Quilez, "filtering procedurals"); w = filter width per axis, in cells
float checkers(vec2 p, vec2 w)
{
    w = max(w, 0.0001);
    vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
    return 0.5 - 0.5 * i.x * i.y;
}

// floor colour at p seen along rd by a ray cone whose width there is cw
vec3 floorAlbedo(vec3 p, vec3 rd, float cw)
{
    // the footprint stretches by 1/|rd.y| along the view direction on the plane
    vec2  dir = normalize(rd.xz + 1e-5);
    float str = 1.0 / max(abs(rd.y), 0.02) - 1.0;
    vec2  w   = cw * (1.0 + str * abs(dir)) / CHECK_S;
    // the scene's 3D checker includes floor(y/s) = -2 on this floor: c_1 sits on even xz cells
    float f = checkers(p.xz / CHECK_S, w);
    return mix(CHECK_1, CHECK_2, f);
}

// direct + ambient light on an opaque surface (floor or mirror); refl = share of the mirrored ray
vec3 shade(vec3 pos, vec3 nor, vec3 rd, float id, float cw, out vec3 refl)
{
    vec3  lv  = LIGHT_P - pos;
    float ld  = length(lv);
    vec3  lig = lv / ld;
    vec3  hal = normalize(lig - rd);
    float nl  = clamp(dot(nor, lig), 0.0, 1.0);
    float nv  = clamp(dot(nor, -rd), 0.0, 1.0);
    float nh  = clamp(dot(nor, hal), 0.0, 1.0);
    float fre = pow(1.0 - nv, 5.0);
    float occ = calcAO(pos, nor);

    vec3 sha = vec3(0.0);
    if (nl > 0.0001) sha = softShadow(pos + nor * 0.002, lig, ld, 24.0) * glassShadow(pos, lig);

    vec3 col;
    if (id < 1.5)
    {
        vec3 alb = floorAlbedo(pos, rd, cw);
        float sky = 0.5 + 0.5 * nor.y;
        col  = alb * (1.2 * LIGHT_C * nl * sha + 1.3 * SKY_COL * sky * occ);
        col += 0.25 * LIGHT_C * sha * pow(nh, 40.0) * (0.04 + 0.96 * pow(1.0 - dot(hal, lig), 5.0));
        refl = vec3(0.04 + 0.5 * fre) * occ;                  // glazed tiles: a faint Fresnel mirror
    }
    else
    {
        // mirror: dark base, sharp highlight, and 90% (rising to 100% at grazing) of the reflected ray
        float bou = clamp(0.5 - 0.5 * nor.y, 0.0, 1.0);
        col  = MIRROR_KD * (LIGHT_C * nl * sha + SKY_COL * occ + BOU_COL * bou * occ);
        col += 3.0 * LIGHT_C * sha * pow(nh, 256.0);
        refl = vec3(mix(MIRROR_KR, 1.0, fre)) * mix(0.6, 1.0, occ);
    }
    return col;
}

// what the glass surface reflects: the sky, and the checkered floor below the horizon
vec3 glassEnv(vec3 ro, vec3 rd, float cw)
{
    if (rd.y < 0.0)
    {
        float t = (-1.0 - ro.y) / rd.y;
        vec3  p = ro + rd * t;
        vec3  lig = normalize(LIGHT_P - p);
        vec3  c = floorAlbedo(p, rd, cw + 0.002 * t) * (1.2 * LIGHT_C * lig.y + 1.3 * SKY_COL);
        return mix(c, HORIZON, 1.0 - exp(-0.02 * t));
    }
    return skyColor(rd);
}

vec3 render(vec3 ro, vec3 rd, float pxAng)
{
    vec3  col = vec3(0.0);
    vec3  thr = vec3(1.0);
    float dist = 0.0;                       // length of the path so far, for the ray cone

    for (int bounce = 0; bounce < 3; bounce++)   // primary ray + 2 bounces
    {
        vec2 h = raymarch(ro, rd);
        if (h.x < 0.0) { col += thr * skyColor(rd); break; }

        float t   = h.x;
        vec3  pos = ro + rd * t;
        dist += t;
        float cw  = pxAng * dist * (bounce == 0 ? 1.0 : 1.6);
        float fog = 1.0 - exp(-0.0006 * dist * dist);
        vec3  fogCol = HORIZON * 0.95;

        if (h.y > 2.5)
        {
            // glass: Fresnel reflection (k_r on top of Schlick) + refraction through the whole sphere
            vec3  nor = normalize(pos - SPH_GLASS.xyz);
            float nv  = clamp(dot(nor, -rd), 0.0, 1.0);
            float F   = GLASS_KR + (1.0 - GLASS_KR) * pow(1.0 - nv, 5.0);
            vec3  rfl = reflect(rd, nor);
            vec3  lig = normalize(LIGHT_P - pos);
            vec3  hi  = LIGHT_C * 3.0 * pow(clamp(dot(rfl, lig), 0.0, 1.0), 96.0 * 4.0);
            col += thr * mix(F * glassEnv(pos, rfl, cw) + hi, fogCol, fog);

            vec3  r1 = refract(rd, nor, 1.0 / GLASS_ETA);
            vec3  oc = pos - SPH_GLASS.xyz;
            float chord = -2.0 * dot(oc, r1);
            vec3  pex = pos + r1 * chord;
            vec3  nex = normalize(pex - SPH_GLASS.xyz);
            vec3  r2  = refract(r1, -nex, GLASS_ETA);
            if (dot(r2, r2) < 0.5) r2 = reflect(r1, -nex);
            vec3 kt = pow(GLASS_KT, vec3(chord / (2.0 * SPH_GLASS.w) + 0.5));
            thr *= (1.0 - F) * kt * (1.0 - fog);
            dist += chord;
            ro = pex + r2 * 0.002;
            rd = r2;
        }
        else
        {
            vec3 nor = (h.y < 1.5) ? vec3(0.0, 1.0, 0.0) : calcNormal(pos);
            vec3 refl;
            vec3 c = shade(pos, nor, rd, h.y, cw, refl);
            col += thr * mix(c, fogCol, fog);
            thr *= refl * (1.0 - fog);
            ro = pos + nor * 0.002;
            rd = reflect(rd, nor);
        }
        if (max(thr.x, max(thr.y, thr.z)) < 0.01) break;
    }
    return col;
}

void mainImage(out vec4 fragColor, in vec2 fragCoord)
{
    vec3 ww = normalize(CAM_TGT - CAM_POS);
    vec3 uu = normalize(cross(vec3(0.0, 1.0, 0.0), ww));
    vec3 vv = cross(ww, uu);
    float fl = 1.0 / tan(radians(FOV) * 0.5);
    float pxAng = 2.0 / (iResolution.y * fl * float(AA));    // angular size of one sub-pixel

    vec3 tot = vec3(0.0);
    for (int m = 0; m < AA; m++)
    for (int n = 0; n < AA; n++)
    {
        vec2 o = vec2(float(m), float(n)) / float(AA) - 0.5 + 0.5 / float(AA);
        vec2 p = (2.0 * (fragCoord + o) - iResolution.xy) / iResolution.y;
        vec3 rd = normalize(mat3(uu, vv, ww) * vec3(p, fl));
        vec3 col = render(CAM_POS, rd, pxAng);
        col = col / (1.0 + 0.12 * col);
        tot += pow(clamp(col, 0.0, 1.0), vec3(0.4545));
    }
    tot /= float(AA * AA);

    tot = tot * 0.7 + 0.3 * tot * tot * (3.0 - 2.0 * tot);
    vec2 q = fragCoord / iResolution.xy;
    tot *= 0.65 + 0.35 * pow(16.0 * q.x * q.y * (1.0 - q.x) * (1.0 - q.y), 0.12);

    fragColor = vec4(tot, 1.0);
}
