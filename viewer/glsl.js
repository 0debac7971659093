// The viewer's shaders. The vertex shader that places the feathers from
// their records is the repository's reference shader,
// shaders/feather_instance.vert (GLSL 330 core), fetched as it is: WebGL2
// speaks GLSL ES 3.00, whose vertex stage accepts everything that file
// uses (layout locations on inputs, uint and ivec attributes, array
// constructors, a loop with a bound known only at run time), so the port
// changes only the version line and adds the default precisions ES asks
// for. There is no second copy to keep in step; the render test checks
// that nothing else changed and that glslangValidator compiles the result.

// The version line the reference shader must start with.
export const REFERENCE_VERSION = '#version 330 core';

// What replaces it in GLSL ES 3.00 (three.js writes the version line itself
// when a material's glslVersion is GLSL3, so `withVersion` is false there).
export const ES_HEADER = ['precision highp float;', 'precision highp int;'];

// The reference shader's source in GLSL ES 3.00.
export function toGlslEs300(source, { withVersion = true } = {}) {
  const lines = source.split('\n');
  if (lines[0].trim() !== REFERENCE_VERSION) {
    throw new Error(`the reference shader starts with "${lines[0]}", not "${REFERENCE_VERSION}"`);
  }
  return [...(withVersion ? ['#version 300 es'] : []), ...ES_HEADER, ...lines.slice(1)].join('\n');
}

// The copied-out geometry and the body: positions and normals as they are,
// with the same outputs and uniform as the reference shader.
export const PLAIN_VERTEX = `precision highp float;
precision highp int;
uniform mat4 u_model_view_projection;
in vec3 position;
in vec3 normal;
in vec2 uv;
out vec2 v_uv;
out vec3 v_normal;
void main() {
    v_uv = uv;
    v_normal = normal;
    gl_Position = u_model_view_projection * vec4(position, 1.0);
}
`;

// One fragment shader for both paths: a base colour (root to tip along u,
// a darker shaft at v = 0.5 for feathers) lit by an ambient term and two
// directional lights on the side of the triangle facing the camera (the
// card is counter-clockwise seen from +z, the side away from the skin).
// u_lit = 0 drops the normal altogether (flat colour), which the test
// uses to tell differences of position from differences of shading.
export const FEATHER_FRAGMENT = `precision highp float;
precision highp int;
uniform vec3 u_root_color;
uniform vec3 u_tip_color;
uniform float u_shaft;
uniform float u_lit;
uniform vec3 u_ambient;
uniform vec3 u_light_dir[2];
uniform vec3 u_light_color[2];
in vec2 v_uv;
in vec3 v_normal;
out vec4 frag_color;
void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    vec3 base = mix(u_root_color, u_tip_color, clamp(v_uv.x, 0.0, 1.0));
    base *= 1.0 - u_shaft * 0.5 * (1.0 - smoothstep(0.02, 0.07, abs(v_uv.y - 0.5)));
    vec3 light = u_ambient;
    for (int i = 0; i < 2; ++i) {
        light += u_light_color[i] * max(dot(n, u_light_dir[i]), 0.0);
    }
    vec3 c = mix(base, base * light, u_lit);
    frag_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
`;
