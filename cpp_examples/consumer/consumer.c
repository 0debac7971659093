/* C99 consumer of an installed Plumage: only <plumage.h> from the library.
 * Dresses a sphere, steps one squashed frame, validates it. Exit 0 on success. */
#include <plumage.h>

#include "sphere.h"

#include <stdio.h>
#include <stdlib.h>

static int fail(const PlumageSystem* sys, uint32_t st, const char* what) {
    char msg[512];
    plumage_system_last_error(sys, msg, sizeof msg);
    fprintf(stderr, "consumer.c: %s: %s: %s\n", what, plumage_status_name(st), msg);
    return 1;
}

int main(void) {
    static float rest[3 * SPHERE_VERTICES], frame[3 * SPHERE_VERTICES];
    static uint32_t tri[3 * SPHERE_TRIANGLES];
    PlumageConfig cfg;
    PlumageMeshDesc mesh;
    PlumageValidation val;
    PlumageSystem* sys = NULL;
    size_t feathers = 0, floats = 0;
    float* xyz;
    uint32_t st;

    if (plumage_abi_version() != PLUMAGE_ABI_VERSION) {
        fprintf(stderr, "consumer.c: library ABI %u, header ABI %u\n", (unsigned)plumage_abi_version(),
                (unsigned)PLUMAGE_ABI_VERSION);
        return 1;
    }
    sphere_fill(rest, tri);
    plumage_config_init(&cfg);
    cfg.target_feathers = 150;
    cfg.threads = 1;
    plumage_mesh_desc_init(&mesh);
    mesh.positions = rest;
    mesh.vertex_count = SPHERE_VERTICES;
    mesh.indices = tri;
    mesh.triangle_count = SPHERE_TRIANGLES;
    st = plumage_system_create(&cfg, &mesh, &sys);
    if (st != PLUMAGE_STATUS_OK) return fail(NULL, st, "create");

    sphere_squash(rest, frame, 0.2f);
    st = plumage_system_step(sys, frame, SPHERE_VERTICES);
    if (st != PLUMAGE_STATUS_OK) return fail(sys, st, "step");

    val.struct_size = sizeof val;
    st = plumage_system_validate(sys, &val);
    if (st != PLUMAGE_STATUS_OK) return fail(sys, st, "validate");
    plumage_system_feather_count(sys, &feathers);

    /* The copy-out convention: ask the size, then copy. */
    st = plumage_system_feather_triangles(sys, NULL, 0, &floats);
    /* Nine floats a triangle, at least two triangles (a kite) a feather. */
    if (st != PLUMAGE_STATUS_BUFFER_TOO_SMALL || floats % 9 != 0 || floats < 18 * feathers)
        return fail(sys, st, "triangle size query");
    xyz = (float*)malloc(floats * sizeof *xyz);
    if (xyz == NULL) return 1;
    st = plumage_system_feather_triangles(sys, xyz, floats, &floats);
    free(xyz);
    if (st != PLUMAGE_STATUS_OK) return fail(sys, st, "triangles");
    plumage_system_destroy(sys);

    printf("plumage %s (ABI %u): %zu feathers on a %d-triangle sphere, after a step: %llu intersecting pairs, "
           "coverage %.3f\n",
           plumage_version(), (unsigned)plumage_abi_version(), feathers, SPHERE_TRIANGLES,
           (unsigned long long)val.intersecting_pairs, val.coverage);
    if (feathers < 50 || val.intersecting_pairs != 0) {
        fprintf(stderr, "consumer.c: wanted at least 50 feathers and 0 intersecting pairs\n");
        return 1;
    }
    return 0;
}
