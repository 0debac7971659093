#version 330 core
// Plumage: the reference vertex shader for drawing feathers as instances of
// one template card. Each instance is one PlumageFeatherInstance (36 bytes,
// plumage_system_feather_instances); the card is PlumageFeatherTemplate
// (plumage_system_feather_template), uploaded once. The convention is the one
// documented on PlumageFeatherInstance in plumage.h; the CPU twin of this
// shader is place() in cpp_examples/tests/instancing_test.cpp (and
// InstanceRecord::place in src/feather/record.rs).
//
// Vertex layout (one buffer of the card, one of records with divisor 1):
//   location 0  card position      3 x float            PlumageFeatherTemplate.positions
//   location 1  card uv            2 x float            PlumageFeatherTemplate.uvs
//   location 2  card segment       1 x uint  (integer)  PlumageFeatherTemplate.vertex_segments
//   location 3  record root        3 x float,  offset  0, stride 36
//   location 4  record rotation    4 x short,  offset 12, stride 36 (integer attribute)
//   location 5  record size        2 x float,  offset 20, stride 36 (length, width)
//   location 6  record bends       3 x short,  offset 28, stride 36 (integer attribute)
// The snorm16 values come in as integers (glVertexAttribIPointer) and are
// scaled here, so the result does not depend on which rule for normalised
// shorts the driver follows.

const float PLUMAGE_INSTANCE_BEND_RANGE = 3.14159265358979; // as in plumage.h

uniform int u_segments;                 // PlumageFeatherTemplate.segments, 1 to 4
uniform mat4 u_model_view_projection;   // the mesh's model space to clip space

layout(location = 0) in vec3 a_card;    // x along the unbent shaft (0 root, 1 tip), y across (+-0.5), z 0
layout(location = 1) in vec2 a_uv;
layout(location = 2) in uint a_segment; // the shaft segment that carries this vertex
layout(location = 3) in vec3 i_root;
layout(location = 4) in ivec4 i_rotation;
layout(location = 5) in vec2 i_size;
layout(location = 6) in ivec3 i_bends;

out vec2 v_uv;
out vec3 v_normal;  // of the flat segment the vertex lies on (the copied-out geometry averages them at joints)

// q * v * conj(q) for a unit quaternion q = (x, y, z, w).
vec3 rotate(vec4 q, vec3 v) {
    vec3 t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

void main() {
    float bends[3] = float[3](float(i_bends.x), float(i_bends.y), float(i_bends.z));
    int k = int(a_segment);
    float step = i_size.x / float(u_segments);

    // Along the bent shaft in the feather's own x-z plane: the whole
    // segments before k, each turned by the bends so far, then part of k.
    vec2 at = vec2(0.0);
    float angle = 0.0;
    for (int j = 0; j < k; ++j) {
        if (j > 0) {
            angle += bends[j - 1] * (PLUMAGE_INSTANCE_BEND_RANGE / 32767.0);
        }
        at += step * vec2(cos(angle), sin(angle));
    }
    if (k > 0) {
        angle += bends[k - 1] * (PLUMAGE_INSTANCE_BEND_RANGE / 32767.0);
    }
    float along = (a_card.x - float(k) / float(u_segments)) * i_size.x;
    vec2 shaft = at + along * vec2(cos(angle), sin(angle));

    vec4 q = normalize(vec4(i_rotation) / 32767.0);
    vec3 world = i_root + rotate(q, vec3(shaft.x, a_card.y * i_size.y, shaft.y));
    v_normal = rotate(q, vec3(-sin(angle), 0.0, cos(angle)));
    v_uv = a_uv;
    gl_Position = u_model_view_projection * vec4(world, 1.0);
}
