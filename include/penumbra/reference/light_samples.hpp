// penumbra/reference/light_samples.hpp — the oracle's light-sample sets, now part of
// penumbra/light_samples.hpp (one implementation).
//
// Integration summary
//   Needs:    GLM and the C++17 standard library (no GPU, no GL, no libm transcendental function).
//   Produces: reference::sphereLightSamples(center, radius, count, seed),
//             reference::diskLightSamples(center, normal, radius, count, seed) and
//             reference::rectLightSamples(corner, edge_u, edge_v, nu, nv): world-space samples of a
//             ball, a disk and a parallelogram, bit-identical to what this header always gave
//             (golden hashes in tests/visibility_test.cpp). Their radius-0 rule is kept: exactly ONE
//             sample at the centre whatever `count` is (a point light). They are declared and
//             documented in penumbra/light_samples.hpp, next to the K-set API
//             (makeLightSampleSets, lightFrame, lightSampleSet) built on the same internals.
//   Hooks:    none.
#ifndef PENUMBRA_REFERENCE_LIGHT_SAMPLES_HPP
#define PENUMBRA_REFERENCE_LIGHT_SAMPLES_HPP

#include <penumbra/light_samples.hpp>

#endif
