#!/usr/bin/env python3
"""bench/ablate/variants.py IQC.frag OUT_PREFIX — edited copies of an iqc Shadertoy shader for an ablation on a
GPU (bench/ablate.sh), each drawing the same picture as the original (the script checks), each changing one
thing in the runtime's code:

  _hitid   the march keeps no instance ids for the step cap (best_id, last_id): the hit's id is taken at the
           break, the step cap's from the scene evaluated again at its sample (extra call sites)
  _noid    the march loop evaluates a distance-only copy of the scene function (no id carried through its
           minima) and finds the id after the loop (as _hitid)
  _normal  the normal's taps evaluate the whole scene instead of the hit instance's distance
  _shadow  the shadow loops' `return 0.0` inside the loop become breaks (scenes with shadows)

A variant that does not apply to the shader (no such code) is not written. Stop 35's ablation on an H200
(docs/accuracy.md, "On a GPU") found the march's returns-to-breaks worth 1.25x -> 1.11x of the hand-written
shader's frame on a few shapes, and the distance-only loop 1.11x -> 0.90x: _hitid against _noid tells which
part of that the GPU pays for.
"""
import re
import sys


def span(s, sig):
    i = s.index(sig)
    return i, s.index('\n}\n', i) + 3


def replace_function(s, sig, text):
    i, j = span(s, sig)
    return s[:i] + text + s[j:]


def scene_distance_only(s):
    """iqc_scene_d: iqc_scene's minima without the ids (only the plain form `res_k = (a < res_j.x) ? vec2(a, n)
    : res_j` is understood; None otherwise)."""
    i, j = span(s, 'vec2 iqc_scene(vec3 p) {')
    body = s[i:j].replace('vec2 iqc_scene(vec3 p) {', 'float iqc_scene_d(vec3 p) {')
    body = re.sub(r'vec2 res = vec2\((\w+), [0-9.]+\);', r'float res = \1;', body)
    body = re.sub(r'vec2 (res_\d+) = \((\w+) < (res\w*)\.x\) \? vec2\(\2, [0-9.]+\) : \3;', r'float \1 = \2 < \3 ? \2 : \3;', body)
    if 'vec2' in body:
        return None
    return s[:j] + '\n' + body + s[j:]


MARCH = '''float iqc_march(vec3 ro, vec3 rd, out int id, out int steps) {
    float t = 0.0, best_t = -1.0, best = 1.0e20, last_t = 0.0, last = 1.0e20, prev = 1.0e20, hit_id = -1.0;
    id = -1;
    steps = 0;
    float t_far = FAR;
    for (int i = 0; i < IQC_MAX_STEPS && t <= t_far; i++) {
        EVAL
        steps++;
        float e = iqc_eps(t);
        prev = last;
        last = DN;
        last_t = t;
        if (last < e) { HIT break; }
        if (last < best) { best = last; best_t = t; }
        t += D;
    }
    float last_id = last < iqc_eps(last_t) ? HITID : iqc_scene(ro + last_t * rd).y;
    return iqc_march_end(last, last_t, last_id, t > t_far, best / IQC_HIT, best_t, iqc_scene(ro + best_t * rd).y,
                         last <= prev, id);
}
'''


def march(s, distance_only):
    if 'best / IQC_HIT, best_t, best_id, last <= prev, id);' not in s or 'if (i == 0 && h.x < 0.0)' in s or 'iqc_segment' in s:
        return None  # a relative tolerance, an inside-start test or segment tracing: not handled
    far = 'iqc_far(ro, rd, t)' if 'float iqc_far(' in s else 'IQC_MAX_DIST'
    m = MARCH.replace('FAR', far)
    if distance_only:
        if 'iqc_lipschitz' in s:
            return None  # the nearness needs the id
        s = scene_distance_only(s)
        if s is None:
            return None
        m = (m.replace('EVAL', 'float h = iqc_scene_d(ro + t * rd);').replace('DN', 'abs(h)').replace('HIT ', '')
             .replace('HITID', 'iqc_scene(ro + last_t * rd).y').replace('D;', 'h;'))
    else:
        m = (m.replace('EVAL', 'vec2 h = iqc_scene(ro + t * rd);').replace('DN', 'iqc_nearness(h)')
             .replace('HIT ', 'hit_id = h.y; ').replace('HITID', 'hit_id').replace('D;', 'h.x;'))
    return replace_function(s, 'float iqc_march(vec3 ro', m)


def normal(s):
    if 'float iqc_normal_tap(vec3 p, int id) {' not in s:
        return None
    return replace_function(s, 'float iqc_normal_tap(vec3 p, int id) {',
                            'float iqc_normal_tap(vec3 p, int id) {\n    return iqc_scene(p).x;\n}\n')


def shadow(s):
    t = s.replace('if (!leaving || h <= last) return 0.0;', 'if (!leaving || h <= last) { res = 0.0; break; }')
    if 'if (!leaving || v <= last) return 0.0;' in t:
        i, j = span(t, 'float iqc_shadow(')
        f = (t[i:j].replace('if (!leaving || v <= last) return 0.0;', 'if (!leaving || v <= last) { lit = 0.0; break; }')
             .replace('float t = 0.0, last = -1.0;', 'float t = 0.0, last = -1.0, lit = 1.0;')
             .replace('    return 1.0;\n}', '    return lit;\n}'))
        t = t[:i] + f + t[j:]
    return t if t != s else None


if __name__ == '__main__':
    src, prefix = sys.argv[1], sys.argv[2]
    s = open(src).read()
    for name, v in (('hitid', march(s, False)), ('noid', march(s, True)), ('normal', normal(s)), ('shadow', shadow(s))):
        if v is not None:
            open(f'{prefix}_{name}.frag', 'w').write(v)
