// Prints one hash over everything the conservative-raster CPU twins compute (hull kind, count,
// spilled flag, vertices, emitted positions, box; the spill predicate) for a fixed set of
// triangles. Built twice — default flags and -ffp-contract=fast -march=native — and ctest compares
// the two outputs (conservative_raster_twin_bits.cmake): the twins round every product the GLSL
// marks `precise` opaquely, so FMA contraction cannot change a bit. Inputs are built from integers
// with exact operations only (ldexp, small-integer conversions), so they are identical too.
#include <penumbra/conservative_raster.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace {

uint64_t state = 0x9e3779b97f4a7c15ull;
uint32_t next() {  // xorshift64*: integers only
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return static_cast<uint32_t>((state * 2685821657736338717ull) >> 32);
}
// A float in (-2^e, 2^e) with 20 significant bits, built exactly.
float value(int e) { return std::ldexp(static_cast<float>(static_cast<int32_t>(next() >> 11) - (1 << 20)), e - 20); }

uint64_t hash = 1469598103934665603ull;
void mix(const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) hash = (hash ^ b[i]) * 1099511628211ull;
}

}  // namespace

int main() {
    uint64_t spills = 0, triangles = 0;
    for (auto variant : {penumbra::ConservativeVariant::Fixed6, penumbra::ConservativeVariant::Exact}) {
        penumbra::ConservativeRasterOptions o;
        o.viewport_x = 3;
        o.viewport_y = -5;
        o.viewport_width = 37;
        o.viewport_height = 29;
        o.variant = variant;
        o.subpixel_bits = 8;
        o.near_plane = glm::vec4(0.125f, -0.375f, 0.75f, 0.875f);  // a general plane: all four products
        const penumbra::ConservativeRasterSetup setup = penumbra::conservativeRasterSetup(o);
        for (int i = 0; i < 200000; ++i) {
            glm::vec4 c[3];
            const int reach = static_cast<int>(next() % 24) - 4;  // NDC reach 2^-4 .. 2^19: slivers to 1e7-px vertices
            for (auto& v : c) {
                const float w = std::ldexp(static_cast<float>(1 + next() % 255), -6);  // (0, 4)
                v = glm::vec4(value(reach) * w, value(reach) * w, value(1) * w, (next() % 16 == 0) ? -w : w);
            }
            switch (next() % 8) {
                case 0: c[2] = c[0]; break;                      // coincident
                case 1: c[2].x = c[1].x = c[0].x; break;         // axis-aligned collinear (w may differ)
                case 2: c[1] = c[0], c[2] = c[0]; break;         // a point
                default: break;
            }
            const penumbra::ConservativeHull hull = penumbra::conservativeHull(c, setup);
            const bool spill = penumbra::conservativeNeedsSpill(c[0], c[1], c[2], setup);
            spills += spill;
            ++triangles;
            mix(&hull.kind, sizeof hull.kind);
            mix(&hull.count, sizeof hull.count);
            mix(&hull.spilled, sizeof hull.spilled);
            mix(&spill, sizeof spill);
            mix(hull.pixels.data(), sizeof(glm::vec2) * static_cast<size_t>(hull.count));
            mix(hull.positions.data(), sizeof(glm::vec4) * static_cast<size_t>(hull.count));
            mix(&hull.box, sizeof hull.box);
        }
    }
    std::printf("%llu triangles, %llu spilled, twin hash %016llx\n", static_cast<unsigned long long>(triangles),
                static_cast<unsigned long long>(spills), static_cast<unsigned long long>(hash));
    return 0;
}
