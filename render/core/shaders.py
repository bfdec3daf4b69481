"""The lit shaders of the 3D worlds (both bowling videos and the crash video): flat-shaded solids
as (V, 9) float32 rows (position, normal, colour; :mod:`nbst.render.core.solids` builds them)
drawn under one light, with one shading function (:data:`SHADE`) that the bowling ball's
textured shader includes too; and the scene video's (any MJCF): the same shading with a
directional light's shadow map, a checker on planes, translucent colours and flat-coloured lines
(:data:`SCENE_VS`, :data:`SCENE_FS`), and the shadow map's depth pass (:data:`DEPTH_VS`, :data:`DEPTH_FS`).

GLSL text only.
"""
from __future__ import annotations

__all__ = ["SHADE", "SOLID_FS", "SOLID_VS", "SCENE_VS", "SCENE_FS", "DEPTH_VS", "DEPTH_FS"]

#: The solids' vertex shader: world position and normal through ``u_model``, ``u_vp`` the camera.
SOLID_VS = """#version 330
uniform mat4 u_vp;
uniform mat4 u_model;
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_color;
out vec3 v_normal;
out vec3 v_world;
out vec3 v_color;
void main() {
    vec4 w = u_model * vec4(in_pos, 1.0);
    v_world = w.xyz;
    v_normal = mat3(u_model) * in_normal;
    v_color = in_color;
    gl_Position = u_vp * w;
}
"""
#: The 3D worlds' shading, one GLSL function for every lit shader (the pins, lanes and vehicles of
#: SOLID_FS, the textured ball of :mod:`nbst.render.bowling.lane`): ambient 0.35 plus 0.65 Lambert,
#: and a Blinn-Phong highlight (exponent 40, weight 0.3); the normal is turned towards the eye
#: (the pins' meshes and the lane's flat solids are drawn from either side).
SHADE = """
vec3 shade(vec3 color, vec3 normal, vec3 world, vec3 light, vec3 eye) {
    vec3 n = normalize(normal);
    vec3 v = normalize(eye - world);
    if (dot(n, v) < 0.0) n = -n;
    float diff = max(dot(n, light), 0.0);
    vec3 h = normalize(light + v);
    float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.3;
    return color * (0.35 + 0.65 * diff) + vec3(spec);
}
"""
SOLID_FS = """#version 330
uniform vec3 u_light;
uniform vec3 u_eye;
in vec3 v_normal;
in vec3 v_world;
in vec3 v_color;
out vec4 f_color;
""" + SHADE + """
void main() {
    f_color = vec4(shade(v_color, v_normal, v_world, u_light, u_eye), 1.0);
}
"""


#: Geoms in their own frame (``u_model``: the pose), the camera ``u_vp``; where the shadow map is
#: read, a little off the surface (along its normal and towards the light: no self-shadowing acne).
SCENE_VS = """#version 330
uniform mat4 u_vp;
uniform mat4 u_model;
uniform mat4 u_light_vp;
uniform float u_offset;
uniform vec3 u_light;
in vec3 in_pos;
in vec3 in_normal;
out vec3 v_normal;
out vec3 v_world;
out vec4 v_shadow;
void main() {
    vec4 w = u_model * vec4(in_pos, 1.0);
    vec3 n = normalize(mat3(u_model) * in_normal);
    v_world = w.xyz;
    v_normal = n;
    // the shadow map is looked up a little off the surface (along its normal, towards the light)
    v_shadow = u_light_vp * vec4(w.xyz + u_offset * (1.5 * n + u_light), 1.0);
    gl_Position = u_vp * w;
}
"""
#: Lit (``u_lit`` 1: shaded, the shadow map, a checker of ``u_checker`` m on planes) or flat colour
#: (0: outlines); ``u_color``'s alpha for the translucent.
SCENE_FS = """#version 330
uniform vec4 u_color;
uniform vec3 u_light;
uniform vec3 u_eye;
uniform float u_lit;
uniform float u_checker;
uniform sampler2DShadow u_shadow;
uniform float u_texel;
in vec3 v_normal;
in vec3 v_world;
in vec4 v_shadow;
out vec4 f_color;
void main() {
    if (u_lit < 0.5) { f_color = vec4(u_color.rgb * u_color.a, u_color.a); return; }
    vec3 c = u_color.rgb;
    if (u_checker > 0.0) {
        vec2 q = floor(v_world.xy / u_checker);
        c *= (mod(q.x + q.y, 2.0) < 0.5) ? 1.0 : 0.9;
    }
    vec3 s = v_shadow.xyz / v_shadow.w * 0.5 + 0.5;
    // four bilinear lookups (the comparison filtered: 16 texels), half a texel apart
    float lit = 0.0;
    for (int i = 0; i < 4; i++)
        lit += texture(u_shadow, vec3(s.xy + (vec2(i / 2, i % 2) - 0.5) * u_texel, s.z));
    lit *= 0.25;
    if (s.x < 0.0 || s.x > 1.0 || s.y < 0.0 || s.y > 1.0 || s.z > 1.0) lit = 1.0;
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_world);
    if (dot(n, v) < 0.0) n = -n;
    float diff = max(dot(n, u_light), 0.0) * (0.25 + 0.75 * lit);
    vec3 h = normalize(u_light + v);
    float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.3 * lit;
    vec3 col = c * (0.35 + 0.65 * diff) + vec3(spec);
    f_color = vec4(col * u_color.a, u_color.a);
}
"""
#: The shadow map's pass: depth only, from the light.
DEPTH_VS = """#version 330
uniform mat4 u_light_vp;
uniform mat4 u_model;
in vec3 in_pos;
void main() { gl_Position = u_light_vp * u_model * vec4(in_pos, 1.0); }
"""
DEPTH_FS = """#version 330
void main() {}
"""
