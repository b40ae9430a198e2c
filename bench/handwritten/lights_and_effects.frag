// Hand-written reference for examples/lights_and_effects.iq: a red ball, a Fresnel mirror ball and a glass
// ball on a dark floor. Written by hand (not compiler output): sun with soft shadows, sky and bounce fill,
// GGX speculars, analytic sphere AO, 2 reflection bounces, refraction with a glass caustic, fog, sRGB.

#define AA 2

const vec3  CAM_POS = vec3(0.0, 1.5, -5.0);
const vec3  CAM_TGT = vec3(0.0, 0.0, 0.0);
const float FOV     = 50.0;

const vec3  SUN_DIR = vec3(-0.55, 0.7, -0.45);   // towards the sun (normalized in code)
const vec3  SUN_COL = vec3(1.5, 1.35, 1.15);
const vec3  SKY_COL = vec3(0.16, 0.22, 0.34);
const vec3  BOU_COL = vec3(0.20, 0.15, 0.10);
const vec3  ZENITH  = vec3(0.12, 0.28, 0.65);
const vec3  HORIZON = vec3(0.55, 0.64, 0.80);

// spheres: centre, radius
const vec4  SPH_RED    = vec4(-1.6,  0.0, 0.5, 1.0);
const vec4  SPH_MIRROR = vec4( 0.6, -0.2, 1.5, 0.8);
const vec4  SPH_GLASS  = vec4( 1.2, -0.5, -1.0, 0.5);
const vec3  GLASS_KT   = vec3(0.9, 0.95, 0.9);
const float GLASS_ETA  = 1.5;

#define MAT_FLOOR  1.0
#define MAT_RED    2.0
#define MAT_MIRROR 3.0
#define MAT_GLASS  4.0

//------------------------------------------------------------------ scene

float sdSphere(vec3 p, vec4 s) { return length(p - s.xyz) - s.w; }

vec2 opU(vec2 a, vec2 b) { return (a.x < b.x) ? a : b; }

vec2 map(vec3 p)
{
    vec2 res = vec2(p.y + 1.0, MAT_FLOOR);
    res = opU(res, vec2(sdSphere(p, SPH_RED),    MAT_RED));
    res = opU(res, vec2(sdSphere(p, SPH_MIRROR), MAT_MIRROR));
    res = opU(res, vec2(sdSphere(p, SPH_GLASS),  MAT_GLASS));
    return res;
}

// opaque occluders only (the glass is handled analytically in the shadow)
float mapOpaque(vec3 p)
{
    return min(p.y + 1.0, min(sdSphere(p, SPH_RED), sdSphere(p, SPH_MIRROR)));
}

vec3 calcNormal(vec3 p)
{
    vec2 e = vec2(1.0, -1.0) * 0.0005;
    return normalize(e.xyy * map(p + e.xyy).x + e.yyx * map(p + e.yyx).x +
                     e.yxy * map(p + e.yxy).x + e.xxx * map(p + e.xxx).x);
}

vec2 raymarch(vec3 ro, vec3 rd)
{
    float t = 0.0;
    for (int i = 0; i < 200; i++)
    {
        vec2 h = map(ro + rd * t);
        if (abs(h.x) < 0.0001 * (1.0 + t)) return vec2(t, h.y);
        t += h.x;
        if (t > 60.0) break;
    }
    return vec2(-1.0);
}

float softShadow(vec3 ro, vec3 rd, float k)
{
    float res = 1.0;
    float t = 0.01;
    for (int i = 0; i < 64; i++)
    {
        float h = mapOpaque(ro + rd * t);
        res = min(res, k * h / t);
        t += clamp(h, 0.01, 0.3);
        if (res < 0.001 || t > 12.0) break;
    }
    res = clamp(res, 0.0, 1.0);
    return res * res * (3.0 - 2.0 * res);
}

// The glass ball in the sun's path: a dim, tinted shadow with the ball lens' caustic in the middle.
vec3 glassShadow(vec3 p, vec3 lig)
{
    vec3  c = SPH_GLASS.xyz - p;
    float r = SPH_GLASS.w;
    float s = dot(c, lig);                       // distance along the sun ray to the ball's centre
    if (s < 0.0) return vec3(1.0);
    float d = length(c - lig * s);               // distance of the sun ray from the centre
    float inside = 1.0 - smoothstep(0.9 * r, 1.05 * r, d);
    // ball lens: paraxial focus at eta*r/(2(eta-1)) from the centre
    float f = GLASS_ETA * r / (2.0 * (GLASS_ETA - 1.0));
    float w = r * max(abs(s - f) / f, 0.22);
    float caus = min(r * r / (w * w), 7.0) * exp(-d * d / (w * w));
    vec3  trans = GLASS_KT * GLASS_KT * (0.12 + 0.8 * caus);
    return mix(vec3(1.0), trans, inside);
}

// analytic sphere occlusion (Quilez)
float sphOcclusion(vec3 pos, vec3 nor, vec4 sph)
{
    vec3  di = sph.xyz - pos;
    float l  = length(di);
    float nl = dot(nor, di / l);
    float h  = l / sph.w;
    return clamp(nl, 0.0, 1.0) / (h * h);
}

float calcAO(vec3 pos, vec3 nor)
{
    float occ = 1.0;
    occ *= 1.0 - sphOcclusion(pos, nor, SPH_RED);
    occ *= 1.0 - sphOcclusion(pos, nor, SPH_MIRROR);
    occ *= 1.0 - 0.6 * sphOcclusion(pos, nor, SPH_GLASS);
    // the floor below a ball's underside
    occ *= clamp(0.5 + 0.5 * nor.y + 0.5 * (pos.y + 1.0), 0.0, 1.0);
    return clamp(occ, 0.0, 1.0);
}

//------------------------------------------------------------------ lighting

vec3 skyColor(vec3 rd, vec3 lig)
{
    float y = max(rd.y, 0.0);
    vec3 col = mix(HORIZON, ZENITH, pow(y, 0.4));
    col = mix(col, HORIZON * 0.85, smoothstep(0.0, -0.3, rd.y));
    float sun = clamp(dot(rd, lig), 0.0, 1.0);
    col += SUN_COL * (0.25 * pow(sun, 12.0) + 6.0 * pow(sun, 1200.0));
    return col;
}

float ggx(float nh, float nl, float nv, float rough)
{
    float a  = rough * rough;
    float a2 = a * a;
    float d  = nh * nh * (a2 - 1.0) + 1.0;
    float D  = a2 / (3.14159 * d * d);
    float V  = 0.5 / max(1e-5, nl * sqrt(nv * nv * (1.0 - a2) + a2) + nv * sqrt(nl * nl * (1.0 - a2) + a2));
    return D * V;
}

void getMaterial(float id, out vec3 alb, out float metal, out float rough, out float kr)
{
    if (id < 1.5)      { alb = vec3(0.18, 0.17, 0.16); metal = 0.0; rough = 0.60; kr = 0.02; }
    else if (id < 2.5) { alb = vec3(0.75, 0.12, 0.08); metal = 0.0; rough = 0.35; kr = 0.0;  }
    else               { alb = vec3(0.90, 0.90, 0.90); metal = 1.0; rough = 0.15; kr = 0.85; }
}

// direct + ambient lighting of an opaque surface; returns the colour and, in refl, the share of the
// mirror-reflected ray to add
vec3 shade(vec3 pos, vec3 nor, vec3 rd, float id, out vec3 refl)
{
    vec3 lig = normalize(SUN_DIR);
    vec3 alb; float metal, rough, kr;
    getMaterial(id, alb, metal, rough, kr);

    vec3  hal = normalize(lig - rd);
    float nl  = clamp(dot(nor, lig), 0.0, 1.0);
    float nv  = max(1e-4, dot(nor, -rd));
    float nh  = clamp(dot(nor, hal), 0.0, 1.0);
    float vh  = clamp(dot(-rd, hal), 0.0, 1.0);
    vec3  f0  = mix(vec3(0.04), alb, metal);
    vec3  F   = f0 + (1.0 - f0) * pow(1.0 - vh, 5.0);
    vec3  Fa  = f0 + (max(vec3(1.0 - rough), f0) - f0) * pow(1.0 - nv, 5.0);

    float occ = calcAO(pos, nor);
    vec3  sha = vec3(0.0);
    if (nl > 0.0001)
        sha = softShadow(pos + nor * 0.002, lig, 14.0) * glassShadow(pos, lig);

    // sun
    vec3 col = SUN_COL * sha * nl * ((1.0 - metal) * alb + 3.14159 * ggx(nh, nl, nv, rough) * F);
    // sky dome
    float sky = 0.5 + 0.5 * nor.y;
    col += 1.6 * SKY_COL * sky * occ * ((1.0 - metal) * alb + Fa * (1.0 - kr));
    // bounce from the ground / away from the sun
    float bou = clamp(0.3 + 0.7 * dot(nor, normalize(vec3(-lig.x, 0.0, -lig.z))), 0.0, 1.0)
              * clamp(1.0 - nor.y, 0.0, 1.0);
    col += 1.4 * BOU_COL * bou * occ * (1.0 - metal) * alb;
    // a touch of rim light from the sky
    col += 0.5 * SKY_COL * pow(1.0 - nv, 3.0) * occ * (1.0 - metal) * (1.0 - kr);

    // mirror share (Fresnel rising to 1 at grazing), rough surfaces see it weaker, occlusion hides it
    float fr = pow(1.0 - nv, 5.0);
    refl = (kr > 0.0) ? mix(vec3(kr) * mix(vec3(1.0), alb, metal), vec3(1.0), fr * (1.0 - rough) * 0.8) * occ
                      : vec3(0.0);
    return col;
}

// cheap reflection seen by the glass surface: the sky, with the floor below the horizon
vec3 glassEnv(vec3 ro, vec3 rd, vec3 lig)
{
    if (rd.y < 0.0)
    {
        float t = (-1.0 - ro.y) / rd.y;
        vec3  p = ro + rd * t;
        vec3  c = vec3(0.18, 0.17, 0.16) * (SUN_COL * glassShadow(p, lig) * lig.y + 1.6 * SKY_COL);
        return mix(c, HORIZON, 1.0 - exp(-0.012 * t));
    }
    return skyColor(rd, lig);
}

vec3 render(vec3 ro, vec3 rd)
{
    vec3 lig = normalize(SUN_DIR);
    vec3 col = vec3(0.0);
    vec3 thr = vec3(1.0);

    for (int bounce = 0; bounce < 3; bounce++)    // primary ray + 2 bounces
    {
        vec2 h = raymarch(ro, rd);
        if (h.x < 0.0) { col += thr * skyColor(rd, lig); break; }

        float t   = h.x;
        vec3  pos = ro + rd * t;
        float fog = 1.0 - exp(-0.012 * t);
        vec3  fogCol = HORIZON * 0.95;

        if (h.y > 3.5)
        {
            // glass ball: Fresnel reflection + refraction straight through the sphere (exact exit point)
            vec3  nor = normalize(pos - SPH_GLASS.xyz);
            float nv  = clamp(dot(nor, -rd), 0.0, 1.0);
            float F   = 0.04 + 0.96 * pow(1.0 - nv, 5.0);
            vec3  rfl = reflect(rd, nor);
            vec3  hi  = SUN_COL * 4.0 * pow(clamp(dot(rfl, lig), 0.0, 1.0), 300.0);
            col += thr * (1.0 - fog) * (F * glassEnv(pos, rfl, lig) + hi);
            col += thr * fog * fogCol;

            vec3  r1 = refract(rd, nor, 1.0 / GLASS_ETA);
            vec3  oc = pos - SPH_GLASS.xyz;
            float chord = -2.0 * dot(oc, r1);
            vec3  pex = pos + r1 * chord;
            vec3  nex = normalize(pex - SPH_GLASS.xyz);
            vec3  r2  = refract(r1, -nex, GLASS_ETA);
            if (dot(r2, r2) < 0.5) r2 = reflect(r1, -nex);
            // transmission per colour, applied as Beer absorption along the chord
            vec3 kt = pow(GLASS_KT, vec3(chord / (2.0 * SPH_GLASS.w) + 0.5));
            thr *= (1.0 - F) * kt * (1.0 - fog);
            ro = pex + r2 * 0.002;
            rd = r2;
        }
        else
        {
            vec3 nor = (h.y < 1.5) ? vec3(0.0, 1.0, 0.0) : calcNormal(pos);
            vec3 refl;
            vec3 c = shade(pos, nor, rd, h.y, refl);
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

    vec3 tot = vec3(0.0);
    for (int m = 0; m < AA; m++)
    for (int n = 0; n < AA; n++)
    {
        vec2 o = vec2(float(m), float(n)) / float(AA) - 0.5 + 0.5 / float(AA);
        vec2 p = (2.0 * (fragCoord + o) - iResolution.xy) / iResolution.y;
        vec3 rd = normalize(mat3(uu, vv, ww) * vec3(p, fl));
        vec3 col = render(CAM_POS, rd);
        col = col / (1.0 + 0.12 * col);                      // soft shoulder for the highlights
        tot += pow(clamp(col, 0.0, 1.0), vec3(0.4545));      // sRGB-ish gamma
    }
    tot /= float(AA * AA);

    tot = tot * 0.7 + 0.3 * tot * tot * (3.0 - 2.0 * tot);   // gentle contrast
    vec2 q = fragCoord / iResolution.xy;
    tot *= 0.65 + 0.35 * pow(16.0 * q.x * q.y * (1.0 - q.x) * (1.0 - q.y), 0.12);

    fragColor = vec4(tot, 1.0);
}
