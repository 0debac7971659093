/* A closed UV sphere for the consumer programs (valid C99 and C++). */
#ifndef CONSUMER_SPHERE_H
#define CONSUMER_SPHERE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#define SPHERE_RINGS 16
#define SPHERE_SEGMENTS 32
#define SPHERE_VERTICES (2 + (SPHERE_RINGS - 1) * SPHERE_SEGMENTS)
#define SPHERE_TRIANGLES (2 * SPHERE_SEGMENTS * (SPHERE_RINGS - 1))

/* Unit sphere around the origin, y up, triangles facing outwards.
 * `xyz` holds 3 * SPHERE_VERTICES floats, `tri` 3 * SPHERE_TRIANGLES indices. */
static inline void sphere_fill(float* xyz, uint32_t* tri) {
    const double pi = 3.14159265358979323846;
    const uint32_t north = 0, south = SPHERE_VERTICES - 1;
    size_t v = 0, t = 0;
    int i, j;
    xyz[v++] = 0.0f, xyz[v++] = 1.0f, xyz[v++] = 0.0f;
    for (i = 1; i < SPHERE_RINGS; ++i) {
        double th = pi * i / SPHERE_RINGS;
        for (j = 0; j < SPHERE_SEGMENTS; ++j) {
            double ph = 2.0 * pi * j / SPHERE_SEGMENTS;
            xyz[v++] = (float)(sin(th) * cos(ph));
            xyz[v++] = (float)cos(th);
            xyz[v++] = (float)(sin(th) * sin(ph));
        }
    }
    xyz[v++] = 0.0f, xyz[v++] = -1.0f, xyz[v++] = 0.0f;
#define SPHERE_AT(ring, seg) ((uint32_t)(1 + ((ring) - 1) * SPHERE_SEGMENTS + ((seg) % SPHERE_SEGMENTS)))
    for (j = 0; j < SPHERE_SEGMENTS; ++j) {
        tri[t++] = north, tri[t++] = SPHERE_AT(1, j + 1), tri[t++] = SPHERE_AT(1, j);
        for (i = 1; i + 1 < SPHERE_RINGS; ++i) {
            uint32_t a = SPHERE_AT(i, j), b = SPHERE_AT(i, j + 1), c = SPHERE_AT(i + 1, j), d = SPHERE_AT(i + 1, j + 1);
            tri[t++] = a, tri[t++] = b, tri[t++] = c;
            tri[t++] = c, tri[t++] = b, tri[t++] = d;
        }
        tri[t++] = SPHERE_AT(SPHERE_RINGS - 1, j), tri[t++] = SPHERE_AT(SPHERE_RINGS - 1, j + 1), tri[t++] = south;
    }
#undef SPHERE_AT
}

/* The sphere squashed along y and bulged in x: a frame's deformed positions. */
static inline void sphere_squash(const float* rest, float* out, float amount) {
    size_t k;
    for (k = 0; k < SPHERE_VERTICES; ++k) {
        out[3 * k + 0] = rest[3 * k + 0] * (1.0f + 0.5f * amount);
        out[3 * k + 1] = rest[3 * k + 1] * (1.0f - amount);
        out[3 * k + 2] = rest[3 * k + 2];
    }
}

#endif
