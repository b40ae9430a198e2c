// A self-checking Shadertoy shader for the WGSL translation (tests/browser/wgsl.test.mjs): each check computes
// a value through one construct glslang writes as structured SPIR-V — loops with break and continue, nested
// loops, do-while, switch with fall-through and a shared case, early returns, short-circuit && and || with
// side effects, ?: , out/inout parameters, arrays indexed at run time, matrices, inverses, integer division and
// remainder, shifts, bit operations, GLSL's mod — against the answer worked out by hand. The pixel is green
// when every check passes; otherwise red, with blue = (index of the first failing check) / 255.

int calls = 0;
bool bump(bool v) { calls++; return v; }

float sum_until(int n, int skip, int stop) {
    float s = 0.0;
    for (int i = 0; i < n; i++) {
        if (i == skip) continue;
        if (i == stop) break;
        s += float(i);
    }
    return s;
}

int first_square_over(int limit) {
    for (int i = 0; ; i++) {
        if (i * i > limit) return i;
    }
    return -1;
}

void split(float x, out float whole, inout float acc) {
    whole = floor(x);
    acc += x - whole;
}

int classify(int k) {
    int r = 0;
    switch (k) {
        case 0: r = 10; break;
        case 1:
        case 2: r = 20; break;
        case 3: r = 30;  // falls through
        case 4: r += 5; break;
        default: r = -1;
    }
    return r;
}

void mainImage(out vec4 fragColor, in vec2 fragCoord) {
    // Zeros the compiler cannot see through: glslang folds constant expressions, so every operand below
    // involves one of these, and the operations reach SPIR-V (and the translation) as instructions.
    float Z = fragCoord.x < -1.0 ? 1.0 : 0.0;
    int IZ = int(Z);
    uint UZ = uint(IZ);
    int failed = 0;
    int k = 0;
    // 1. for with continue and break: 0+1+3+4 (2 skipped, stop at 5)
    k++; if (failed == 0 && sum_until(10 + IZ, 2 + IZ, 5 + IZ) != 8.0) failed = k;
    // 2. nested loops with an inner break: pairs (i, j) with j < i, i < 5: 0+1+2+3+4 = 10
    int pairs = 0;
    for (int i = IZ; i < 5; i++) for (int j = IZ; j < 5; j++) { if (j >= i) break; pairs++; }
    k++; if (failed == 0 && pairs != 10) failed = k;
    // 3. do-while runs once even when the condition is false at once
    int d = IZ;
    do { d += 7; } while (d < 0);
    k++; if (failed == 0 && d != 7) failed = k;
    // 4. while loop
    int w = 100 + IZ; int steps = IZ;
    while (w > 1) { w /= 3; steps++; }
    k++; if (failed == 0 && (w != 1 || steps != 4)) failed = k;
    // 5. early return from an infinite loop
    k++; if (failed == 0 && first_square_over(50 + IZ) != 8) failed = k;
    // 6. switch: shared case, fall-through, default
    k++; if (failed == 0 && (classify(IZ) != 10 || classify(2 + IZ) != 20 || classify(3 + IZ) != 35 || classify(4 + IZ) != 5 || classify(9 + IZ) != -1)) failed = k;
    // 7. && and || short-circuit: bump runs only when needed
    calls = 0;
    bool a = bump(Z > 0.5) && bump(Z < 0.5);
    bool b = bump(Z < 0.5) || bump(Z > 0.5);
    bool c = bump(Z < 0.5) && bump(Z > 0.5);
    k++; if (failed == 0 && (a || !b || c || calls != 4)) failed = k;
    // 8. ?: picks one side
    float t = fragCoord.x >= 0.0 ? 2.5 : -1.0;
    k++; if (failed == 0 && t != 2.5) failed = k;
    // 9. out and inout parameters
    float whole, acc = 1.0;
    split(3.25 + Z, whole, acc);
    k++; if (failed == 0 && (whole != 3.0 || acc != 1.25)) failed = k;
    // 10. an array written and read at run-time indices
    float arr[6];
    for (int i = 0; i < 6; i++) arr[i] = float(i * i);
    int idx = int(t) + 2;  // 4
    k++; if (failed == 0 && (arr[idx] != 16.0 || arr[idx - 3] != 1.0)) failed = k;
    // 11. a const array indexed at run time
    const vec3 table[3] = vec3[3](vec3(1.0, 2.0, 3.0), vec3(4.0, 5.0, 6.0), vec3(7.0, 8.0, 9.0));
    k++; if (failed == 0 && table[idx - 3].z != 6.0) failed = k;
    // 12. matrices: column-major construction, products, transpose
    mat3 m = mat3(1.0 + Z, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0);
    vec3 mv = m * vec3(1.0, Z, 0.0);
    vec3 vm = vec3(1.0, 0.0, Z) * m;
    k++; if (failed == 0 && (mv != vec3(1.0, 2.0, 3.0) || vm != vec3(1.0, 4.0, 7.0) || transpose(m)[0] != vec3(1.0, 4.0, 7.0))) failed = k;
    // 13. inverses (2x2, 3x3, 4x4) times the matrix give the identity
    mat2 m2 = mat2(4.0 + Z, 3.0, 6.0, 3.0);
    mat4 m4 = mat4(2.0 + Z, 0.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 1.0, 4.0, 0.0, 1.0, 2.0, 3.0, 1.0);
    mat3 e3 = inverse(m) * m; mat2 e2 = inverse(m2) * m2; mat4 e4 = inverse(m4) * m4;
    float err = 0.0;
    for (int i = 0; i < 4; i++) for (int j = 0; j < 4; j++) {
        float id = i == j ? 1.0 : 0.0;
        err = max(err, abs(e4[i][j] - id));
        if (i < 3 && j < 3) err = max(err, abs(e3[i][j] - id));
        if (i < 2 && j < 2) err = max(err, abs(e2[i][j] - id));
    }
    k++; if (failed == 0 && err > 1e-4) failed = k;
    // 14. integer division and remainder (C's: toward zero), shifts and bit operations
    int n = -7 + IZ; int seven = 7 + IZ, six = 6 + IZ, five = 5 + IZ;
    k++; if (failed == 0 && (n / 2 != -3 || seven / 2 != 3 || seven % 3 != 1 || (five << 2) != 20 || ((-16 + IZ) >> 2) != -4 ||
                             (six & 3) != 2 || (six | 3) != 7 || (six ^ 3) != 5 || ~IZ != -1)) failed = k;
    // 15. unsigned arithmetic and a logical shift
    uint u = 0xF0000000u + UZ;
    k++; if (failed == 0 && ((u >> 28) != 15u || u / 16u != 0x0F000000u || uint(idx) * 3u != 12u)) failed = k;
    // 16. GLSL's mod takes the divisor's sign; fract, floor, sign
    k++; if (failed == 0 && (mod(-1.0 + Z, 3.0) != 2.0 || mod(5.5 + Z, 2.0) != 1.5 || floor(-0.5 + Z) != -1.0 || sign(-3.0 + Z) != -1.0 ||
                             fract(2.25 + Z) != 0.25)) failed = k;
    // 17. vector swizzles, component writes and comparisons
    vec4 v = vec4(1.0 + Z, 2.0, 3.0, 4.0);
    v.yw = v.wy;
    v[idx - 4] = 9.0;
    k++; if (failed == 0 && (v != vec4(9.0, 4.0, 3.0, 2.0) || any(lessThan(v.xy, vec2(5.0))) == false)) failed = k;
    // 18. a struct with an array member, copied and changed
    struct S { float x; int n[2]; };
    S s1 = S(1.5 + Z, int[2](3 + IZ, 4));
    S s2 = s1;
    s2.n[1] = 8;
    k++; if (failed == 0 && (s1.n[1] != 4 || s2.n[1] != 8 || s2.x != 1.5)) failed = k;
    // 19. built-ins: smoothstep, step, clamp, mix, length, dot, cross, normalize, reflect
    k++; if (failed == 0 && (smoothstep(0.0, 1.0, 0.5 + Z) != 0.5 || step(1.0, 0.5 + Z) != 0.0 || clamp(5.0 + Z, 0.0, 2.0) != 2.0 ||
                             mix(2.0, 4.0, 0.25 + Z) != 2.5 || length(vec2(3.0 + Z, 4.0)) != 5.0 ||
                             cross(vec3(1.0 + Z, 0.0, 0.0), vec3(0.0, 1.0, 0.0)) != vec3(0.0, 0.0, 1.0) ||
                             reflect(vec2(1.0 + Z, -1.0), vec2(0.0, 1.0)) != vec2(1.0, 1.0))) failed = k;
    // 20. a loop whose counter is also changed in its body
    int visits = 0;
    for (int i = IZ; i < 20; i += 2) {
        if (i == 4) i += 3;  // 0, 2, 4→7, 9, 11, ..., 19: 9 visits
        visits++;
    }
    k++; if (failed == 0 && visits != 9) failed = k;
    fragColor = failed == 0 ? vec4(0.0, 1.0, 0.0, 1.0) : vec4(1.0, 0.0, float(failed) / 255.0, 1.0);
}
