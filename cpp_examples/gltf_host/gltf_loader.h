// Reading a .glb or .gltf file into a tinygltf model, with a one-line
// reason (InputError) for anything unreadable or unsupported.
#pragma once

#include <string>

#include <tiny_gltf.h>

namespace plumage_host {

// Loads `path` (GLB container or JSON with embedded or external buffers).
// Images are not decoded: the host never needs their pixels. Refuses files
// whose extensionsRequired names an extension the host cannot honour.
tinygltf::Model load_gltf_file(const std::string& path);

// Required extensions the host can read faithfully.
bool is_supported_required_extension(const std::string& name);

}  // namespace plumage_host
