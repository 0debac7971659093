#include "accessor.h"

#include "errors.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <limits>

namespace plumage_host {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "glTF buffers are little-endian; this reader assumes a little-endian host");

// Far above any real mesh, low enough that element counts times strides
// never overflow and that an accessor without a buffer view (all zeros, so
// its count costs nothing in the file) cannot ask for gigabytes.
constexpr size_t kMaxValues = size_t{1} << 26;

struct Bytes {
    const unsigned char* data = nullptr;
    size_t size = 0;
};

[[noreturn]] void fail(const std::string& what, const std::string& why) { throw InputError(what + ": " + why); }

size_t component_size(int type) {
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;  // INT and DOUBLE are not glTF 2.0 accessor types
    }
}

int components_of(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
    }
}

// One component at p. Normalized integers map to [0, 1] or [-1, 1] (glTF 2.0, 3.11).
double read_component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
        uint8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return normalized ? v / 4294967295.0 : v;
    }
    default: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    }
}

// The bytes of buffer view `index`, checked against its buffer.
Bytes view_bytes(const tinygltf::Model& model, int index, const std::string& what) {
    if (index < 0 || static_cast<size_t>(index) >= model.bufferViews.size()) {
        fail(what, "buffer view " + std::to_string(index) + " does not exist");
    }
    const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(index)];
    if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size()) {
        fail(what, "buffer view " + std::to_string(index) + " names a missing buffer");
    }
    const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset) {
        fail(what, "buffer view " + std::to_string(index) + " runs past the end of its buffer");
    }
    return {data.data() + view.byteOffset, view.byteLength};
}

// The dense part: the buffer view's elements, honouring its byte stride.
void read_dense(const tinygltf::Model& model, const tinygltf::Accessor& acc, size_t element_size, int components,
                const std::string& what, std::vector<double>& out) {
    const Bytes bytes = view_bytes(model, acc.bufferView, what);
    const size_t csize = component_size(acc.componentType);
    const size_t declared = model.bufferViews[static_cast<size_t>(acc.bufferView)].byteStride;
    const size_t stride = declared != 0 ? declared : element_size;
    if (stride < element_size || stride % csize != 0) fail(what, "byte stride " + std::to_string(stride) + " does not fit its elements");
    if (acc.count == 0) return;
    if (acc.byteOffset > bytes.size || stride * (acc.count - 1) + element_size > bytes.size - acc.byteOffset) {
        fail(what, "accessor runs past the end of its buffer view");
    }
    const size_t n = static_cast<size_t>(components);
    for (size_t i = 0; i < acc.count; ++i) {
        const unsigned char* element = bytes.data + acc.byteOffset + i * stride;
        for (size_t c = 0; c < n; ++c) out[i * n + c] = read_component(element + c * csize, acc.componentType, acc.normalized);
    }
}

// Sparse substitution (glTF 2.0, 3.6.2.3): `count` indices, then tightly packed values.
void apply_sparse(const tinygltf::Model& model, const tinygltf::Accessor& acc, size_t element_size, int components,
                  const std::string& what, std::vector<double>& out) {
    const auto& sparse = acc.sparse;
    if (sparse.count < 1 || static_cast<size_t>(sparse.count) > acc.count) fail(what, "sparse count out of range");
    if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0) fail(what, "negative sparse byte offset");
    const int index_type = sparse.indices.componentType;
    if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
        fail(what, "sparse indices must be unsigned integers");
    }
    const size_t count = static_cast<size_t>(sparse.count);
    const size_t isize = component_size(index_type);
    const Bytes indices = view_bytes(model, sparse.indices.bufferView, what);
    const Bytes values = view_bytes(model, sparse.values.bufferView, what);
    const size_t ioff = static_cast<size_t>(sparse.indices.byteOffset);
    const size_t voff = static_cast<size_t>(sparse.values.byteOffset);
    if (ioff > indices.size || isize * count > indices.size - ioff) fail(what, "sparse indices run past their buffer view");
    if (voff > values.size || element_size * count > values.size - voff) fail(what, "sparse values run past their buffer view");
    const size_t n = static_cast<size_t>(components);
    const size_t csize = component_size(acc.componentType);
    for (size_t i = 0; i < count; ++i) {
        const double target = read_component(indices.data + ioff + i * isize, index_type, false);
        if (target >= static_cast<double>(acc.count)) fail(what, "sparse index past the accessor's count");
        const size_t t = static_cast<size_t>(target);
        const unsigned char* element = values.data + voff + i * element_size;
        for (size_t c = 0; c < n; ++c) out[t * n + c] = read_component(element + c * csize, acc.componentType, acc.normalized);
    }
}

}  // namespace

AccessorData read_accessor(const tinygltf::Model& model, int index, const std::string& what) {
    if (index < 0 || static_cast<size_t>(index) >= model.accessors.size()) fail(what, "accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& acc = model.accessors[static_cast<size_t>(index)];
    const size_t csize = component_size(acc.componentType);
    const int components = components_of(acc.type);
    if (csize == 0 || components == 0) fail(what, "unsupported accessor component type or element type");
    // Matrix columns of 1- and 2-byte components are padded to 4 bytes; no
    // attribute this host reads uses them, so refuse rather than misread.
    if ((acc.type == TINYGLTF_TYPE_MAT2 || acc.type == TINYGLTF_TYPE_MAT3) && csize < 4) {
        fail(what, "padded small-component matrices are not supported");
    }
    if (acc.count > kMaxValues / static_cast<size_t>(components)) fail(what, "accessor count " + std::to_string(acc.count) + " is too large");
    const size_t element_size = csize * static_cast<size_t>(components);

    AccessorData data;
    data.count = acc.count;
    data.components = components;
    data.values.assign(acc.count * static_cast<size_t>(components), 0.0);  // no buffer view: zeros
    if (acc.bufferView >= 0) read_dense(model, acc, element_size, components, what, data.values);
    if (acc.sparse.isSparse) apply_sparse(model, acc, element_size, components, what, data.values);
    return data;
}

AccessorData read_accessor(const tinygltf::Model& model, int index, int components, const std::string& what) {
    AccessorData data = read_accessor(model, index, what);
    if (data.components != components) {
        fail(what, "expected " + std::to_string(components) + " components per element, got " + std::to_string(data.components));
    }
    return data;
}

std::vector<uint32_t> read_indices(const tinygltf::Model& model, int index, const std::string& what) {
    const AccessorData data = read_accessor(model, index, 1, what);
    const tinygltf::Accessor& acc = model.accessors[static_cast<size_t>(index)];
    if (acc.normalized || acc.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT || acc.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
        acc.componentType == TINYGLTF_COMPONENT_TYPE_SHORT) {
        fail(what, "indices must be unsigned integers");
    }
    std::vector<uint32_t> out;
    out.reserve(data.values.size());
    for (double v : data.values) out.push_back(static_cast<uint32_t>(v));
    return out;
}

}  // namespace plumage_host
