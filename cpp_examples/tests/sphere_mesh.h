// The consumer project's sphere (consumer/sphere.h) as a rest mesh for the C++ tests.
#pragma once

#include "plumage.h"
#include "sphere.h"

#include <vector>

struct SphereMesh {
    std::vector<float> rest = std::vector<float>(3 * SPHERE_VERTICES);
    std::vector<uint32_t> tri = std::vector<uint32_t>(3 * SPHERE_TRIANGLES);

    SphereMesh() { sphere_fill(rest.data(), tri.data()); }

    PlumageMeshDesc desc() const {
        PlumageMeshDesc mesh;
        plumage_mesh_desc_init(&mesh);
        mesh.positions = rest.data();
        mesh.vertex_count = SPHERE_VERTICES;
        mesh.indices = tri.data();
        mesh.triangle_count = SPHERE_TRIANGLES;
        return mesh;
    }
};
