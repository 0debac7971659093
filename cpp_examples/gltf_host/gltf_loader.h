// Reading a .glb or .gltf file into a tinygltf model, with a one-line
// reason (InputError) for anything unreadable or unsupported.
#pragma once

#include <string>
#include <vector>

#include <tiny_gltf.h>

namespace plumage_host {

// Loads `path` (GLB container or JSON with embedded or external buffers).
// Images are not decoded: the host never needs their pixels. Refuses files
// whose extensionsRequired names an extension the host cannot honour.
tinygltf::Model load_gltf_file(const std::string& path);

// As load_gltf_file, over the file's `bytes` already in memory: `path`
// names it in messages, external buffers are read from `base_dir`.
tinygltf::Model load_gltf_memory(const std::vector<unsigned char>& bytes, const std::string& path, const std::string& base_dir);

// Required extensions the host can read faithfully.
bool is_supported_required_extension(const std::string& name);

}  // namespace plumage_host
