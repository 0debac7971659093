// Feathers for instancing, as an engine uses them: the template card once,
// then each frame the records and the list of changed feathers. place()
// below expands a record on the CPU step for step as
// shaders/feather_instance.vert does on the GPU; the test compares it with
// the copied-out geometry (within 1e-4 of a feather's length, 1 to 4 shaft
// segments), and checks the changed list against full copies before and
// after each step: a feather not listed is bit for bit as it was.
#include "plumage.h"
#include "plumage.hpp"

#include "check.h"
#include "sphere_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

static_assert(sizeof(PlumageFeatherInstance) <= 40, "a record is at most 40 bytes");
static_assert(sizeof(PlumageFeatherInstance) == 36, "the documented layout");

namespace {

struct Card {
    uint32_t segments = 0;
    std::vector<float> positions;  // 3 per vertex
    std::vector<float> uvs;        // 2 per vertex
    std::vector<uint32_t> indices;
    std::vector<uint32_t> vertex_segments;
};

Card template_card(const PlumageSystem* sys) {
    PlumageFeatherTemplate t;
    plumage_feather_template_init(&t);
    CHECK(plumage_system_feather_template(sys, &t) == PLUMAGE_STATUS_OK);
    Card c;
    c.segments = t.segments;
    c.positions.resize(3 * t.vertex_count);
    c.uvs.resize(2 * t.vertex_count);
    c.indices.resize(3 * t.triangle_count);
    c.vertex_segments.resize(t.vertex_count);
    t.positions = c.positions.data();
    t.positions_capacity = c.positions.size();
    t.uvs = c.uvs.data();
    t.uvs_capacity = c.uvs.size();
    t.indices = c.indices.data();
    t.indices_capacity = c.indices.size();
    t.vertex_segments = c.vertex_segments.data();
    t.vertex_segments_capacity = c.vertex_segments.size();
    CHECK(plumage_system_feather_template(sys, &t) == PLUMAGE_STATUS_OK);
    return c;
}

std::vector<PlumageFeatherInstance> instances(const PlumageSystem* sys) {
    size_t n = 0;
    plumage_system_feather_instances(sys, nullptr, 0, &n);
    std::vector<PlumageFeatherInstance> out(n);
    CHECK(plumage_system_feather_instances(sys, out.data(), out.size(), &n) == PLUMAGE_STATUS_OK);
    return out;
}

std::vector<float> positions(const PlumageSystem* sys) {
    PlumageFeatherGeometry g;
    plumage_feather_geometry_init(&g);
    CHECK(plumage_system_feather_geometry(sys, &g) == PLUMAGE_STATUS_OK);
    std::vector<float> out(3 * static_cast<size_t>(g.vertex_count));
    g.positions = out.data();
    g.positions_capacity = out.size();
    CHECK(plumage_system_feather_geometry(sys, &g) == PLUMAGE_STATUS_OK);
    return out;
}

struct Vec3 {
    float x, y, z;
};

Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// The reference shader's main(), on the CPU: card vertex `v` placed and bent by `r`.
Vec3 place(const PlumageFeatherInstance& r, const Card& card, size_t v) {
    const float bends[3] = {float(r.bends[0]), float(r.bends[1]), float(r.bends[2])};
    const int k = int(card.vertex_segments[v]);
    const float step = r.length / float(card.segments);
    float at_x = 0.0f, at_z = 0.0f, angle = 0.0f;
    for (int j = 0; j < k; ++j) {
        if (j > 0) angle += bends[j - 1] * (PLUMAGE_INSTANCE_BEND_RANGE / 32767.0f);
        at_x += step * std::cos(angle);
        at_z += step * std::sin(angle);
    }
    if (k > 0) angle += bends[k - 1] * (PLUMAGE_INSTANCE_BEND_RANGE / 32767.0f);
    const float along = (card.positions[3 * v] - float(k) / float(card.segments)) * r.length;
    const Vec3 p = {at_x + along * std::cos(angle), card.positions[3 * v + 1] * r.width, at_z + along * std::sin(angle)};
    float q[4];
    float norm = 0.0f;
    for (int i = 0; i < 4; ++i) {
        q[i] = float(r.rotation[i]) / 32767.0f;
        norm += q[i] * q[i];
    }
    norm = std::sqrt(norm);
    const Vec3 u = {q[0] / norm, q[1] / norm, q[2] / norm};
    const float w = q[3] / norm;
    Vec3 t = cross(u, p);
    t = {2.0f * t.x, 2.0f * t.y, 2.0f * t.z};
    const Vec3 ut = cross(u, t);
    return {r.root[0] + p.x + w * t.x + ut.x, r.root[1] + p.y + w * t.y + ut.y, r.root[2] + p.z + w * t.z + ut.z};
}

// Largest distance between the placed cards and the geometry, in feather lengths.
float reconstruction_error(const PlumageSystem* sys, const Card& card) {
    const std::vector<PlumageFeatherInstance> records = instances(sys);
    const std::vector<float> geometry = positions(sys);
    const size_t nv = card.vertex_segments.size();
    CHECK(geometry.size() == 3 * nv * records.size());
    float worst = 0.0f;
    for (size_t f = 0; f < records.size(); ++f) {
        for (size_t v = 0; v < nv; ++v) {
            const Vec3 p = place(records[f], card, v);
            const float* g = &geometry[3 * (f * nv + v)];
            const float d = std::sqrt((p.x - g[0]) * (p.x - g[0]) + (p.y - g[1]) * (p.y - g[1]) + (p.z - g[2]) * (p.z - g[2]));
            if (records[f].length > 0.0f) {
                worst = std::max(worst, d / records[f].length);
            } else if (d != 0.0f) {
                worst = 1.0f;  // a feather left out lies at its root exactly
            }
        }
    }
    return worst;
}

// The sphere with its upper cap waving (y > 0.3) and the rest held still, bit for bit.
std::vector<float> wave(const std::vector<float>& rest, int frame) {
    std::vector<float> out(rest);
    const float phase = 0.4f * float(frame);
    for (size_t k = 0; k < out.size() / 3; ++k) {
        const float y = rest[3 * k + 1];
        if (y > 0.3f) {
            const float a = 0.25f * (y - 0.3f) * std::sin(phase);
            out[3 * k + 0] = rest[3 * k + 0] + a;
            out[3 * k + 2] = rest[3 * k + 2] + 0.5f * a;
        }
    }
    return out;
}

std::vector<uint32_t> changed(const PlumageSystem* sys, uint32_t* all) {
    size_t n = 0;
    const uint32_t st = plumage_system_changed_feathers(sys, nullptr, 0, &n, all);
    std::vector<uint32_t> out(n);
    if (n == 0) {
        CHECK(st == PLUMAGE_STATUS_OK);
        return out;
    }
    CHECK(st == PLUMAGE_STATUS_BUFFER_TOO_SMALL);
    CHECK(plumage_system_changed_feathers(sys, out.data(), out.size(), &n, all) == PLUMAGE_STATUS_OK);
    return out;
}

}  // namespace

int main() {
    const SphereMesh sphere;
    const PlumageMeshDesc mesh = sphere.desc();
    for (uint32_t segments = 1; segments <= PLUMAGE_MAX_SHAFT_SEGMENTS; ++segments) {
        PlumageConfig cfg;
        plumage_config_init(&cfg);
        cfg.target_feathers = 600;
        cfg.threads = 1;
        cfg.shaft_segments = segments;
        PlumageSystem* sys = nullptr;
        CHECK(plumage_system_create(&cfg, &mesh, &sys) == PLUMAGE_STATUS_OK);
        if (!sys) continue;
        const Card card = template_card(sys);
        CHECK(card.segments == segments);
        uint32_t all = 0;
        std::vector<PlumageFeatherInstance> before = instances(sys);
        std::vector<float> before_xyz = positions(sys);
        const std::vector<uint32_t> first = changed(sys, &all);
        CHECK(all == 1 && first.size() == before.size());
        const size_t nv = card.vertex_segments.size();

        float worst = reconstruction_error(sys, card);
        size_t listed = 0, steps = 0, wrongly_unlisted = 0, listed_unchanged = 0;
        for (int frame = 1; frame <= 6; ++frame) {
            const std::vector<float> xyz = wave(sphere.rest, frame);
            CHECK(plumage_system_step(sys, xyz.data(), SPHERE_VERTICES) == PLUMAGE_STATUS_OK);
            worst = std::max(worst, reconstruction_error(sys, card));
            const std::vector<PlumageFeatherInstance> after = instances(sys);
            const std::vector<float> after_xyz = positions(sys);
            const std::vector<uint32_t> list = changed(sys, &all);
            CHECK(all == 0);
            std::vector<char> is_listed(after.size(), 0);
            for (uint32_t f : list) is_listed[f] = 1;
            for (size_t f = 0; f < after.size(); ++f) {
                const bool same_record = std::memcmp(&before[f], &after[f], sizeof(PlumageFeatherInstance)) == 0;
                const bool same_xyz =
                    std::memcmp(&before_xyz[3 * f * nv], &after_xyz[3 * f * nv], 3 * nv * sizeof(float)) == 0;
                if (!is_listed[f] && !(same_record && same_xyz)) ++wrongly_unlisted;
                if (is_listed[f] && same_record && same_xyz) ++listed_unchanged;
            }
            listed += list.size();
            ++steps;
            before = after;
            before_xyz = after_xyz;
        }
        CHECK(wrongly_unlisted == 0);
        CHECK(listed_unchanged == 0);
        CHECK(worst < 1e-4f);
        std::printf("S = %u: %zu feathers, %zu card vertices, largest error %.2e lengths; %.1f %% listed a step\n",
                    segments, before.size(), nv, double(worst), 100.0 * double(listed) / double(steps * before.size()));
        plumage_system_destroy(sys);
    }
    // The same through plumage.hpp.
    PlumageConfig cfg = plumage::default_config();
    cfg.target_feathers = 200;
    cfg.threads = 1;
    plumage::System sys(cfg, sphere.rest, sphere.tri);
    std::vector<uint32_t> list;
    CHECK(sys.changed_feathers(list) && list.size() == sys.feather_count());
    CHECK(sys.feather_instances().size() == sys.feather_count());
    const plumage::FeatherTemplate card = sys.feather_template();
    CHECK(card.segments == cfg.shaft_segments && card.vertex_count() > 0 && card.triangle_count() > 0);
    sys.step(wave(sphere.rest, 1));
    CHECK(!sys.changed_feathers(list) && list.size() < sys.feather_count());
    return plumage_check::finish("instancing_test");
}
