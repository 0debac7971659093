#include "pose_writer.h"

#include "errors.h"

#include <cstdint>
#include <filesystem>

namespace plumage_host {

PoseWriter::PoseWriter(const std::string& path, PlumageConfig cfg, double fps, const std::vector<float>& rest, const std::vector<uint32_t>& indices,
                       const std::vector<double>& times, const VertexMaps& maps)
    : path_(path), frames_expected_(times.size()) {
    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    file_ = std::fopen(path.c_str(), "wb");
    if (file_ == nullptr) throw OutputError("cannot write " + path);
    cfg.progress = nullptr;
    cfg.progress_user_data = nullptr;
    const char magic[8] = {'P', 'L', 'M', 'P', 'O', 'S', 'E', '\0'};
    // The lowest version that holds the blocks present: older readers keep reading what they know.
    const bool types = !maps.feather_type.empty();
    const bool v2 = !maps.layer.empty() || maps.skeleton.has_value();
    const uint32_t head[2] = {types ? 3u : v2 ? 2u : 1u, static_cast<uint32_t>(sizeof cfg)};
    const uint64_t counts[3] = {rest.size() / 3, indices.size() / 3, times.size()};
    const uint32_t mask = (maps.spacing.empty() ? 0u : 1u) | (maps.length.empty() ? 0u : 2u) | (maps.width.empty() ? 0u : 4u) | (maps.flow.empty() ? 0u : 8u) |
                          (maps.layer.empty() ? 0u : 16u) | (maps.skeleton ? 32u : 0u) | (types ? 64u : 0u);
    const uint32_t tail[2] = {mask, 0};
    write(magic, sizeof magic);
    write(head, sizeof head);
    write(counts, sizeof counts);
    write(&fps, sizeof fps);
    write(tail, sizeof tail);
    write(&cfg, sizeof cfg);
    write(rest.data(), rest.size() * sizeof(float));
    write(indices.data(), indices.size() * sizeof(uint32_t));
    write(times.data(), times.size() * sizeof(double));
    for (const std::vector<float>* m : {&maps.spacing, &maps.length, &maps.width, &maps.flow, &maps.layer}) write(m->data(), m->size() * sizeof(float));
    if (maps.skeleton) {
        const SkinSkeleton& k = *maps.skeleton;
        const int32_t head_joint = -1;  // as create_system passes it
        const uint32_t counts_k[2] = {static_cast<uint32_t>(k.joint_count()), k.influences};
        const uint32_t reserved = 0;
        write(counts_k, sizeof counts_k);
        write(&head_joint, sizeof head_joint);
        write(&reserved, sizeof reserved);
        write(k.joint_positions.data(), k.joint_positions.size() * sizeof(float));
        write(k.joint_parents.data(), k.joint_parents.size() * sizeof(int32_t));
        write(k.vertex_joints.data(), k.vertex_joints.size() * sizeof(uint32_t));
        write(k.vertex_weights.data(), k.vertex_weights.size() * sizeof(float));
    }
    if (types) {
        const uint32_t counts_t[2] = {static_cast<uint32_t>(maps.feather_types.size()), 0};
        write(counts_t, sizeof counts_t);
        write(maps.feather_types.data(), maps.feather_types.size() * sizeof(uint32_t));
        write(maps.feather_type.data(), maps.feather_type.size() * sizeof(uint32_t));
    }
}

PoseWriter::~PoseWriter() {
    if (file_ != nullptr) std::fclose(file_);
}

void PoseWriter::write(const void* data, size_t bytes) {
    if (bytes > 0 && std::fwrite(data, 1, bytes, file_) != bytes) throw OutputError("cannot write " + path_);
}

void PoseWriter::add_frame(const std::vector<float>& positions) {
    write(positions.data(), positions.size() * sizeof(float));
    ++frames_written_;
}

void PoseWriter::finish() {
    std::FILE* f = file_;
    file_ = nullptr;
    if (std::fclose(f) != 0 || frames_written_ != frames_expected_) throw OutputError("cannot write " + path_);
}

}  // namespace plumage_host
