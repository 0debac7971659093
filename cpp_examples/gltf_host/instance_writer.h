// Writes what a renderer needs to draw the feathers as instances of one
// card (--instances DIR), frame by frame, for viewer/ and its test. Every
// file is raw little-endian data; DIR/manifest.json names them and gives
// the counts. Frame 0 is the rest pose (after create), frame k the pose
// after the k-th step.
//
//   template.bin         the card (plumage_system_feather_template), once:
//                          float    positions[3 * V]    unit length and width
//                          float    uvs[2 * V]
//                          uint32_t vertex_segments[V]
//                          uint32_t indices[3 * T]
//   body_indices.bin     uint32_t indices[3 * body triangles], once
//   records_NNNN.bin     PlumageFeatherInstance[feathers], 36 bytes each, as
//                        plumage_system_feather_instances copies them out
//   changed_NNNN.bin     uint32_t indices[changed], the feathers that frame's
//                        call may have changed (plumage_system_changed_feathers;
//                        the manifest says when that is every feather)
//   body_NNNN.bin        float positions[3 * body vertices] of that frame
//   geometry_NNNN.bin    the copied-out feathers (plumage_system_feather_geometry),
//                        for the rest pose and the last frame only:
//                          float    positions[3 * n], normals[3 * n], uvs[2 * n]
//                          uint32_t indices[3 * t]   with n = feathers * V, t = feathers * T
#pragma once

#include "plumage.h"
#include "plumage_system.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace plumage_host {

class InstanceWriter {
public:
    // Creates DIR and writes the card and the body's triangles (throws OutputError).
    InstanceWriter(const std::string& dir, const PlumageSystem& sys, const std::vector<float>& body_rest, const std::vector<uint32_t>& body_indices);

    // The system's present frame: `time` in clip seconds (negative: the
    // rest pose), the body's positions, and the copied-out geometry too
    // when `with_geometry`.
    void add_frame(const PlumageSystem& sys, double time, const std::vector<float>& body, bool with_geometry);

    // Writes manifest.json (throws OutputError).
    void finish();

    const std::string& dir() const { return dir_; }

private:
    void write_file(const std::string& name, const std::vector<std::pair<const void*, size_t>>& parts) const;

    std::string dir_;
    size_t feathers_ = 0;
    size_t card_vertices_ = 0;
    size_t card_triangles_ = 0;
    nlohmann::ordered_json manifest_;
    nlohmann::ordered_json frames_ = nlohmann::ordered_json::array();
};

}  // namespace plumage_host
