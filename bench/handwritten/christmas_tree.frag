// Christmas tree — hand-written reference for /work/main/examples/christmas_tree.iq (three needled cone
// tiers with drooping branches, trunk, red baubles, glowing star, snowy fbm hills). Hand-written night
// lighting: warm key + soft shadows, moonlit sky fill, the star as a point light with a halo, AO, fog, sRGB.

#define PI 3.14159265
#define AA 2          // supersampling per axis (1 for speed)

// ---------------------------------------------------------------- helpers

vec3 rotY(vec3 p, float a)           // p rotated about y by -a
{
    float c = cos(a), s = sin(a);
    return vec3(c*p.x + s*p.z, p.y, c*p.z - s*p.x);
}

vec3 repAngular(vec3 p, float n)     // n copies around y, the model lying around +x
{
    float a = 2.0*PI/n*floor(atan(p.z, p.x)*n/(2.0*PI) + 0.5);
    return rotY(p, a);
}

float smin(float a, float b, float k)
{
    float h = max(k - abs(a - b), 0.0);
    return min(a, b) - 0.25*h*h/k;
}

float sdSegment(vec3 v, vec3 e)
{
    return length(v - clamp(dot(v, e)/dot(e, e), 0.0, 1.0)*e);
}

// ---------------------------------------------------------------- snow terrain (value-noise fbm)

float hash2(vec2 x) { return fract(sin(dot(x, vec2(127.1, 311.7)))*43758.5453); }

float vnoise2(vec2 x)
{
    vec2 i = floor(x);
    vec2 f = fract(x);
    vec2 u = f*f*(3.0 - 2.0*f);
    return mix(mix(hash2(i), hash2(i + vec2(1, 0)), u.x),
               mix(hash2(i + vec2(0, 1)), hash2(i + vec2(1, 1)), u.x), u.y);
}

float fbm2(vec2 x)
{
    return 0.5   *(2.0*vnoise2(x) - 1.0)
         + 0.25  *(2.0*vnoise2(2.0*x + vec2(17.1, 3.7)) - 1.0)
         + 0.125 *(2.0*vnoise2(4.0*x + vec2(5.3, 11.9)) - 1.0)
         + 0.0625*(2.0*vnoise2(8.0*x + vec2(13.7, 7.1)) - 1.0);
}

float terrainH(vec2 xz) { return -1.1 + 0.3*fbm2(xz/4.0); }

float sdSnow(vec3 p)
{
    const float G = 8.49*0.3/4.0;
    return (p.y - terrainH(p.xz))/sqrt(1.0 + G*G);
}

// ---------------------------------------------------------------- tree

float tierCone(vec3 q, float a, float h, float r)
{
    return max((length(q.xz)*h + (q.y - a)*r)/sqrt(h*h + r*r), a - h - q.y);
}

float tierBranch(vec3 q, float a, float h, float r)
{
    return sdSegment(q - vec3(0.0, a - 0.45*h, 0.0), vec3(1.1*r, -0.6*h - 0.08, 0.0)) - 0.05;
}

float tier(vec3 q, float a, float h, float r, float phi)
{
    return smin(tierCone(q, a, h, r), tierBranch(repAngular(rotY(q, phi), 9.0), a, h, r), 0.12);
}

float sdTrunk(vec3 p)
{
    return max(length(p.xz) - 0.13, abs(p.y + 0.8) - 0.3);
}

float sdFoliage(vec3 p)
{
    float f = min(tier(p, 1.75, 0.95, 0.55, 0.0),
              min(tier(p, 1.15, 1.05, 0.80, 0.35),
                  tier(p, 0.50, 1.20, 1.05, 0.70)));
    return f + 0.01*sin(30.0*p.x)*sin(30.0*p.y)*sin(30.0*p.z);
}

float bauble(vec3 q, float y, float r, float phi)
{
    return length(repAngular(rotY(q, phi), 6.0) - vec3(r, y, 0.0)) - 0.075;
}

float sdBaubles(vec3 p)
{
    return min(bauble(p, 1.02, 0.62, 0.30),
           min(bauble(p, 0.33, 0.86, 0.65),
               bauble(p, -0.40, 1.05, 1.00)));
}

const vec3 STAR_POS = vec3(0.0, 1.85, 0.0);

float sdStar(vec3 p)
{
    p = abs(p - STAR_POS);
    return (p.x + p.y + p.z - 0.16)*0.57735027;
}

// ---------------------------------------------------------------- scene

// materials: 1 foliage, 2 trunk, 3 baubles, 4 star, 5 snow
vec2 map(vec3 p)
{
    vec2 res = vec2(sdSnow(p), 5.0);

    // the tree's bounding cylinder keeps far-away evaluations cheap
    float bnd = max(length(p.xz) - 1.45, max(-1.2 - p.y, p.y - 2.1));
    if (bnd < res.x)
    {
        // the needles make the foliage ~1.55-Lipschitz: scale its distance down
        float d = sdFoliage(p)/1.55;
        if (d < res.x) res = vec2(d, 1.0);
        d = sdTrunk(p);
        if (d < res.x) res = vec2(d, 2.0);
        d = sdBaubles(p);
        if (d < res.x) res = vec2(d, 3.0);
        d = sdStar(p);
        if (d < res.x) res = vec2(d, 4.0);
    }
    else
    {
        res.x = min(res.x, max(bnd, 0.02));
    }
    return res;
}

vec3 calcNormal(vec3 p, float t)
{
    float h = 0.0005 + 0.0005*t;
    const vec2 k = vec2(1.0, -1.0);
    return normalize(k.xyy*map(p + k.xyy*h).x + k.yyx*map(p + k.yyx*h).x +
                     k.yxy*map(p + k.yxy*h).x + k.xxx*map(p + k.xxx*h).x);
}

// ray march; also returns the closest approach to the star for its halo
vec2 raycast(vec3 ro, vec3 rd, out float starGlow)
{
    float t = 0.0;
    starGlow = 0.0;
    vec2 res = vec2(-1.0);
    for (int i = 0; i < 200; i++)
    {
        vec3 p = ro + rd*t;
        vec2 h = map(p);
        float ds = length(p - STAR_POS);
        starGlow = max(starGlow, 1.0/(1.0 + 60.0*ds*ds));
        if (abs(h.x) < 0.0004*t) { res = vec2(t, h.y); break; }
        t += h.x;
        if (t > 30.0) break;
    }
    return res;
}

float calcSoftshadow(vec3 ro, vec3 rd, float tmax, float k)
{
    float res = 1.0;
    float t = 0.02;
    for (int i = 0; i < 64; i++)
    {
        vec3 p = ro + rd*t;
        float h = map(p).x;
        res = min(res, k*h/t);
        t += clamp(h, 0.015, 0.3);
        if (res < 0.002 || t > tmax) break;
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
        float h = 0.015 + 0.11*float(i);
        float d = map(pos + h*nor).x;
        occ += (h - d)*sca;
        sca *= 0.8;
    }
    return clamp(1.0 - 2.2*occ, 0.0, 1.0);
}

// ---------------------------------------------------------------- shading

const vec3 BACKGROUND = vec3(0.0014, 0.0029, 0.015);
const vec3 LIGHT_POS  = vec3(-4.0, 6.0, -5.0);
const vec3 LIGHT_COL  = vec3(1.0, 0.95, 0.85);
const vec3 STAR_COL   = vec3(1.0, 0.85, 0.3);

vec3 skyColor(vec3 rd)
{
    // deep night blue, faintly lighter at the horizon, with a sprinkle of stars
    float h = clamp(rd.y, 0.0, 1.0);
    vec3 col = mix(vec3(0.012, 0.016, 0.040), BACKGROUND, pow(h, 0.4));
    vec2 sp = vec2(atan(rd.x, rd.z), rd.y)*220.0;
    vec2 cell = floor(sp);
    float r = hash2(cell);
    vec2 o = vec2(hash2(cell + 7.3), hash2(cell + 3.1));
    float s = smoothstep(0.12, 0.0, length(fract(sp) - o)) * step(0.985, r);
    col += s*vec3(0.5, 0.55, 0.7)*(0.3 + 0.7*hash2(cell + 1.7))*smoothstep(0.02, 0.25, rd.y);
    return col;
}

vec3 render(vec3 ro, vec3 rd)
{
    float glow;
    vec2 res = raycast(ro, rd, glow);
    vec3 col = skyColor(rd);

    if (res.x > 0.0)
    {
        float t = res.x;
        float m = res.y;
        vec3 pos = ro + rd*t;
        vec3 nor = calcNormal(pos, t);
        vec3 ref = reflect(rd, nor);

        if (m > 3.5 && m < 4.5)
        {
            // the star: emissive, brightest face-on
            col = STAR_COL*(0.7 + 0.3*abs(dot(nor, rd)))*3.0;
        }
        else
        {
            vec3 alb; float ks = 0.0; float shin = 8.0;
            if (m < 1.5)      { alb = vec3(0.0063, 0.173, 0.015); ks = 0.08; shin = 8.0;
                                // tips of the needles a little lighter, deep in the cone darker
                                alb *= 0.85 + 0.3*smoothstep(-0.015, 0.015, 0.01*sin(30.0*pos.x)*sin(30.0*pos.y)*sin(30.0*pos.z)); }
            else if (m < 2.5) { alb = vec3(0.10, 0.045, 0.02); }
            else if (m < 3.5) { alb = vec3(0.699, 0.0063, 0.0063); ks = 0.612; shin = 64.0; }
            else              { alb = vec3(0.793, 0.832, 1.0); ks = 0.15; shin = 12.0; }

            float occ = calcAO(pos, nor);

            // key light
            vec3  toL = LIGHT_POS - pos;
            float dL  = length(toL);
            vec3  lig = toL/dL;
            float dif = clamp(dot(nor, lig), 0.0, 1.0);
            float sha = (dif > 0.001) ? calcSoftshadow(pos + nor*0.003, lig, 10.0, 10.0) : 0.0;
            dif *= sha;
            vec3  hal = normalize(lig - rd);
            float spc = pow(clamp(dot(nor, hal), 0.0, 1.0), shin)*dif*
                        (0.04 + 0.96*pow(1.0 - clamp(dot(hal, lig), 0.0, 1.0), 5.0));

            // star as a small warm point light (unshadowed, falls off quickly)
            vec3  toS = STAR_POS - pos;
            float dS  = length(toS);
            float sdif = clamp(0.2 + 0.8*dot(nor, toS/dS), 0.0, 1.0)/(1.0 + 2.5*dS*dS);
            float sspc = pow(clamp(dot(ref, toS/dS), 0.0, 1.0), shin);

            // moonlit sky fill, snow bounce, rim
            float sky = sqrt(clamp(0.5 + 0.5*nor.y, 0.0, 1.0))*occ;
            float bou = clamp(0.5 - 0.5*nor.y, 0.0, 1.0)*occ;
            float fre = pow(clamp(1.0 + dot(nor, rd), 0.0, 1.0), 2.0)*occ;

            vec3 lin = vec3(0.0);
            lin += 1.15*dif*LIGHT_COL;
            lin += 0.22*sky*vec3(0.30, 0.42, 1.00);
            lin += 0.12*bou*vec3(0.40, 0.45, 0.60);
            lin += 0.25*fre*vec3(0.30, 0.40, 0.80)*(m > 4.5 ? 0.2 : 1.0);
            lin += 0.9*sdif*STAR_COL*occ;
            lin += 0.04*vec3(0.5, 0.6, 1.0)*(0.3 + 0.7*occ);
            col = alb*lin;
            col += ks*spc*LIGHT_COL*2.5;
            col += ks*sspc*STAR_COL*0.3*occ;

            if (m > 2.5 && m < 3.5)
            {
                // baubles: glossy, reflecting the night sky
                float f = 0.04 + 0.96*pow(clamp(1.0 + dot(nor, rd), 0.0, 1.0), 5.0);
                col += f*0.6*mix(vec3(0.03, 0.05, 0.10), vec3(0.25, 0.30, 0.45), clamp(ref.y, 0.0, 1.0))*occ;
            }
            if (m > 4.5)
            {
                // snow sparkle
                vec3 c = floor(pos*120.0);
                float g = step(0.992, fract(sin(dot(c, vec3(12.9898, 78.233, 37.719)))*43758.5453));
                col += g*dif*vec3(1.0)*0.8*(1.0 - clamp(t/12.0, 0.0, 1.0));
            }
        }

        // fog into the night
        col = mix(col, skyColor(normalize(vec3(rd.x, max(rd.y, 0.0), rd.z))) , 1.0 - exp(-0.065*t));
    }

    // halo around the star
    col += STAR_COL*0.35*pow(glow, 1.5);
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
    vec3 ro = vec3(0.0, 1.0, -5.2);
    vec3 ta = vec3(0.0, 0.35, 0.0);
    mat3 ca = setCamera(ro, ta);
    float fl = 1.0/tan(radians(45.0)*0.5);

    vec3 col = vec3(0.0);
    for (int j = 0; j < AA; j++)
    for (int i = 0; i < AA; i++)
    {
        vec2 o = (vec2(float(i), float(j)) + 0.5)/float(AA) - 0.5;
        vec2 uv = (2.0*(fragCoord + o) - iResolution.xy)/iResolution.y;
        vec3 rd = normalize(ca*vec3(uv, fl));
        vec3 c = render(ro, rd);
        // tone curve, then sRGB
        c = c/(1.0 + 0.3*c);
        col += mix(12.92*c, 1.055*pow(c, vec3(1.0/2.4)) - 0.055, step(0.0031308, c));
    }
    col /= float(AA*AA);

    // vignette
    vec2 q = fragCoord/iResolution.xy;
    col *= 0.65 + 0.35*pow(16.0*q.x*q.y*(1.0 - q.x)*(1.0 - q.y), 0.2);

    fragColor = vec4(clamp(col, 0.0, 1.0), 1.0);
}
