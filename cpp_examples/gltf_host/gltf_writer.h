// Records the run (body and feathers per frame) and writes it as a .glb:
// two meshes whose per-frame positions are morph targets, and one
// animation whose STEP weights switch on one target per frame.
#pragma once

#include "plumage.h"
#include "mesh_union.h"
#include "plumage_system.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace tinygltf {
class Model;
}

namespace plumage_host {

// An encoded image (PNG or JPEG bytes as the input stored them) and how
// it is sampled.
struct EncodedTexture {
    std::vector<unsigned char> bytes;
    std::string mime_type;  // image/png or image/jpeg
    int mag_filter = -1, min_filter = -1;  // -1: not given
    int wrap_s = 10497, wrap_t = 10497;    // REPEAT
};

// The body's material in the .glb: the host's plain default, or the input's
// factors and its base colour texture (with the body's UVs for it).
struct BodyMaterial {
    std::string name = "body";
    std::array<double, 4> base_color{0.78, 0.72, 0.66, 1.0};
    double metallic = 0.0;
    double roughness = 0.8;
    std::array<double, 3> emissive{0, 0, 0};
    bool double_sided = false;
    std::string alpha_mode = "OPAQUE";  // OPAQUE, MASK or BLEND
    double alpha_cutoff = 0.5;
    std::optional<EncodedTexture> base_color_texture;
    int base_color_uv_set = 0;  // n of the input's TEXCOORD_n for it
    std::vector<float> uvs;      // that set, 2 per body vertex (written as TEXCOORD_0)
};

// The material of mesh `mesh_index`'s largest triangle primitive (by index
// count, else vertex count) that has one,
// by its factors (name, base colour, metallic, roughness, emissive,
// double-sided, alpha mode and cutoff) and its base colour texture when its
// image is stored in a buffer view as PNG or JPEG (the caller adds the UVs);
// a base colour texture that cannot be carried keeps the host's grey.
// Nothing when no primitive has one or its factors are out of glTF's ranges.
std::optional<BodyMaterial> input_material(const tinygltf::Model& model, int mesh_index);

class AnimationRecorder {
public:
    // The rest pose: the body soup and the feathers as the library made them.
    AnimationRecorder(std::vector<float> body_rest, std::vector<uint32_t> body_indices, const std::vector<PlumageFeather>& feathers,
                      FeatherMeshData feather_mesh);

    // One stepped frame at `seconds` (clip time).
    void add_frame(double seconds, const std::vector<float>& body, const std::vector<PlumageFeather>& feathers, const FeatherMeshData& feather_mesh);

    // The body's material (the host's default unless set).
    void set_body_material(BodyMaterial m) { body_material_ = std::move(m); }

    // Several meshes dressed as one system: the .glb then holds a body and
    // a feathers mesh per part, named after it (each feather goes with the
    // mesh its root lies on at rest), each body with materials[part].
    void set_parts(std::vector<MeshPart> parts, std::vector<BodyMaterial> materials) {
        parts_ = std::move(parts);
        part_materials_ = std::move(materials);
    }

    // Feathers of a frame that were not at rest (by id); they are left out.
    size_t untracked_feathers() const { return untracked_; }

    // Writes the .glb (throws OutputError): the feathers' mesh carries
    // NORMAL, TEXCOORD_0 (u along the shaft, v across the vanes) and
    // _FEATHER_ID (the feather's index at rest, a float), and every frame's
    // morph target moves positions and normals.
    void write_glb(const std::string& path) const;

private:
    // Positions and normals of a frame in the rest pose's feather order.
    std::pair<std::vector<float>, std::vector<float>> arrange_feathers(const std::vector<PlumageFeather>& feathers, const FeatherMeshData& mesh);

    std::vector<float> body_rest_;
    std::vector<uint32_t> body_indices_;
    FeatherMeshData feather_rest_;
    std::vector<size_t> first_vertex_;  // per rest feather
    std::unordered_map<uint64_t, size_t> slot_of_id_;
    std::vector<double> times_;
    std::vector<std::vector<float>> body_frames_;
    std::vector<std::vector<float>> feather_frames_;
    std::vector<std::vector<float>> normal_frames_;
    size_t untracked_ = 0;
    BodyMaterial body_material_;
    std::vector<uint32_t> rest_triangle_;  // per rest feather: the triangle its root lies on
    std::vector<MeshPart> parts_;
    std::vector<BodyMaterial> part_materials_;
};

}  // namespace plumage_host
