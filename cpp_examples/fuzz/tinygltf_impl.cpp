// tinygltf's implementation compiled into the fuzzer, so that its parser is
// instrumented too (coverage guidance and sanitizer checks), unlike Debian's
// shared libtinygltf the host links. Images are never decoded by the host.
// TINYGLTF_NO_STB_IMAGE and TINYGLTF_NO_STB_IMAGE_WRITE are set for every
// file of the fuzzer (the header's inline constructor names the stb loaders).
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>
