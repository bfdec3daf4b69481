"""The lit shaders of the 3D worlds (both bowling videos and the crash video): flat-shaded solids
as (V, 9) float32 rows (position, normal, colour; :mod:`nbst.render.core.solids` builds them)
drawn under one light, with one shading function (:data:`SHADE`) that the bowling ball's
textured shader includes too.

GLSL text only.
"""
from __future__ import annotations

__all__ = ["SHADE", "SOLID_FS", "SOLID_VS"]

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
