import re, sys
def func_span(s, sig):
    i = s.index(sig); j = s.index('\n}\n', i) + 3
    return i, j
MARCH_BREAK = '''float iqc_march(vec3 ro, vec3 rd, out int id, out int steps) {
    id = -1; steps = 0;
    float t = 0.0;
    float t_far = IQC_FAR_EXPR;
    float best = 1.0e20, best_t = -1.0, best_id = -1.0, last = 1.0e20, last_t = 0.0, last_id = -1.0, prev = 1.0e20;
    for (int i = 0; i < IQC_MAX_STEPS && t <= t_far; i++) {
        vec2 h = iqc_scene(ro + t * rd);
        prev = last; last = iqc_nearness(h); last_t = t; last_id = h.y;
        if (last < iqc_eps(t)) break;
        if (last < best) { best = last; best_t = t; best_id = h.y; }
        t += h.x;
    }
    if (last < iqc_eps(last_t)) { id = int(last_id); return last_t; }
    if (t > t_far) return -1.0;
    return iqc_at_step_cap(best / IQC_HIT, best_t, int(best_id), last, last_t, int(last_id), last <= prev, id);
}
'''
MARCH_NOID = '''float iqc_march(vec3 ro, vec3 rd, out int id, out int steps) {
    id = -1; steps = 0;
    float t = 0.0;
    float t_far = IQC_FAR_EXPR;
    float best = 1.0e20, best_t = -1.0, last = 1.0e20, last_t = 0.0, prev = 1.0e20;
    for (int i = 0; i < IQC_MAX_STEPS && t <= t_far; i++) {
        float h = iqc_scene_d(ro + t * rd);
        prev = last; last = abs(h); last_t = t;
        if (last < iqc_eps(t)) break;
        if (last < best) { best = last; best_t = t; }
        t += h;
    }
    if (last < iqc_eps(last_t)) { id = int(iqc_scene(ro + last_t * rd).y); return last_t; }
    if (t > t_far) return -1.0;
    float best_id = iqc_scene(ro + best_t * rd).y, last_id = iqc_scene(ro + last_t * rd).y;
    return iqc_at_step_cap(best / IQC_HIT, best_t, int(best_id), last, last_t, int(last_id), last <= prev, id);
}
'''
def scene_d(s):
    i, j = func_span(s, 'vec2 iqc_scene(vec3 p) {')
    body = s[i:j]
    body = body.replace('vec2 iqc_scene(vec3 p) {', 'float iqc_scene_d(vec3 p) {')
    body = re.sub(r'vec2 res = vec2\((\w+), [0-9.]+\);', r'float res = \1;', body)
    body = re.sub(r'vec2 (res_\d+) = \((\w+) < (res\w*)\.x\) \? vec2\(\2, [0-9.]+\) : \3;', r'float \1 = min(\2, \3);', body)
    assert 'vec2' not in body, body
    return s[:j] + '\n' + body + s[j:]
def far_expr(s):
    return 'iqc_far(ro, rd, t)' if 'float iqc_far(' in s else 'IQC_MAX_DIST'
def with_march(s, m):
    i, j = func_span(s, 'float iqc_march(vec3 ro')
    m = m.replace('IQC_FAR_EXPR', far_expr(s))
    if 'iqc_far' in m:
        m = m.replace('    for (int i', '    if (t_far < 0.0) return -1.0;\n    for (int i')
    return s[:i] + m + s[j:]
def normal_scene(s):
    i, j = func_span(s, 'float iqc_normal_tap(vec3 p, int id) {')
    return s[:i] + 'float iqc_normal_tap(vec3 p, int id) {\n    return iqc_scene(p).x;\n}\n' + s[j:]
name = sys.argv[1]
s = open(name + '_iqc.frag').read()
open(name + '_march.frag', 'w').write(with_march(s, MARCH_BREAK))
open(name + '_normal.frag', 'w').write(normal_scene(s))
if 'lipschitz' not in s:
    open(name + '_noid.frag', 'w').write(with_march(scene_d(s), MARCH_NOID))
