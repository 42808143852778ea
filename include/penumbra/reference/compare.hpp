// penumbra/reference/compare.hpp — a GPU hard-shadow result against the oracle, sample by sample.
//
// Integration summary
//   Needs:    reference/visibility.hpp (the oracle), the per-sample states a hard-shadow method wrote
//             (one uint per view-sample id, PENUMBRA_AFH_* of alias_free_hard_shared.h) and the
//             very positions it used (vec4 per sample id, as the G-buffer / depth reconstruction
//             produced them: float, converted to double exactly). No GL.
//   Produces: HardComparison: samples compared, shadowed, mismatched (outside oracle ties), ties,
//             the other states' counts and the first few mismatches with the oracle's first
//             crossing, for a report. One function for tests, benchmarks and the demo.
//   Hooks:    none.
//
//   Typical use (after run(), states read back):
//       const penumbra::reference::HardLight light = penumbra::reference::hardLight(frame_light, options.directional_reach);
//       const auto c = penumbra::reference::compareHardStates(oracle, positions, states, light, oracle_options);
//       CHECK(c.mismatched == 0);  // report c.ties next to it
//
//   Two steps when several methods are compared on one set (benchmarks): build the oracle's
//   verdicts once with hardReference(oracle, positions, testedSamples(states), light, options),
//   then compareHardStates(reference, method_states) per method.
//
// Semantics. A sample is compared when the method decided it: state PENUMBRA_AFH_LIT or
// PENUMBRA_AFH_SHADOWED (the one-step form selects them from `states`; the two-step form uses the
// ids the reference was built for, and a state other than SHADOWED there reads as "not shadowed"
// and is also counted in `undecided`). Its segment is receiver = the sample's position, light end =
// the light point (point light) or receiver + reach * direction (directional light), evaluated by
// VisibilityOracle with the caller's options (pass the method's coplanar_epsilon). An oracle tie
// is counted in `ties` and never as a mismatch; otherwise mismatch = (state == SHADOWED) !=
// oracle blocked.
#ifndef PENUMBRA_REFERENCE_COMPARE_HPP
#define PENUMBRA_REFERENCE_COMPARE_HPP

#include <penumbra/detail/shared.hpp>
#include <penumbra/error.hpp>
#include <penumbra/reference/visibility.hpp>
// The state codes live with the shaders (STYLE.md habit 2), like sample_lists.hpp's shared header.
#if defined(__has_include) && __has_include(<penumbra/alias_free_hard/alias_free_hard_shared.h>)
#include <penumbra/alias_free_hard/alias_free_hard_shared.h>
#else
#include "../../../shaders/penumbra/alias_free_hard/alias_free_hard_shared.h"
#endif

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace penumbra {
namespace reference {

/// The light the method used, in the oracle's terms.
struct HardLight {
    bool directional = false;
    glm::dvec3 position{0.0};   ///< point light
    glm::dvec3 direction{0.0};  ///< directional: towards the light (the method's vector, not renormalised)
    double reach = 0.0;         ///< directional: segment length (AliasFreeHardOptions::directional_reach)
};

/// From the pipeline's light vector (w = 1: point, w = 0: direction towards the light) and its
/// directional reach (ignored for a point light; > 0 for a directional one). Float to double is
/// exact, so the oracle sees the very light the GPU used.
inline HardLight hardLight(const glm::vec4& light, float directional_reach = 0.0f) {
    PENUMBRA_CHECK(light.w == 0.0f || light.w == 1.0f, "penumbra::reference::hardLight: light.w = ", light.w,
                   " must be 0 (directional) or 1 (point)");
    HardLight out;
    out.directional = light.w == 0.0f;
    if (out.directional) {
        PENUMBRA_CHECK(directional_reach > 0.0f, "penumbra::reference::hardLight: a directional light needs reach > 0, got ",
                       directional_reach);
        out.direction = glm::dvec3(glm::vec3(light));
        out.reach = static_cast<double>(directional_reach);
    } else {
        out.position = glm::dvec3(glm::vec3(light));
    }
    return out;
}

/// One disagreement, for a report.
struct HardMismatch {
    uint32_t sample = 0;         ///< view-sample id
    glm::dvec3 position{0.0};    ///< the receiver (the method's float position, exactly)
    glm::dvec3 light_end{0.0};   ///< the segment's light end
    bool shadowed = false;       ///< the method's verdict
    bool blocked = false;        ///< the oracle's verdict
    Hit crossing;                ///< the oracle's first crossing of the segment (closestHit on (0, 1))
};

struct HardComparison {
    size_t samples = 0;      ///< samples compared
    size_t shadowed = 0;     ///< of those, the method says SHADOWED
    size_t blocked = 0;      ///< of those, the oracle says blocked (ties included)
    size_t ties = 0;         ///< oracle ties (not compared)
    size_t mismatched = 0;   ///< method != oracle outside ties
    size_t undecided = 0;    ///< compared samples whose state is neither LIT nor SHADOWED (two-step form)
    // Every sample id of `states`, by state (not compared, except as above):
    size_t back_facing = 0;  ///< PENUMBRA_AFH_BACK_FACING
    size_t no_sample = 0;    ///< PENUMBRA_AFH_NO_SAMPLE
    size_t untested = 0;     ///< PENUMBRA_AFH_UNTESTED
    size_t other_state = 0;  ///< any other value (a broken state buffer)
    std::vector<HardMismatch> first_mismatches;  ///< the first max_reported, in sample order

    /// mismatched / (samples - ties); 0 without decided samples.
    double mismatchRate() const {
        const size_t decided = samples - ties;
        return decided ? static_cast<double>(mismatched) / static_cast<double>(decided) : 0.0;
    }
};

/// The oracle's verdicts on a set of samples, computed once.
struct HardReference {
    std::vector<uint32_t> ids;       ///< sample ids, ascending
    std::vector<uint8_t> blocked;    ///< per id
    std::vector<uint8_t> tie;        ///< per id
    std::vector<glm::dvec3> receivers, light_ends;  ///< per id (for reports)
};

/// The ids a method decided: state LIT or SHADOWED.
inline std::vector<uint32_t> testedSamples(const std::vector<uint32_t>& states) {
    std::vector<uint32_t> ids;
    for (size_t id = 0; id < states.size(); ++id) {
        if (states[id] == PENUMBRA_AFH_LIT || states[id] == PENUMBRA_AFH_SHADOWED) ids.push_back(static_cast<uint32_t>(id));
    }
    return ids;
}

/// Oracle verdicts for samples `ids` at positions[id] (xyz). Point lights go through
/// VisibilityOracle::evaluate (threads per options.threads), directional lights through
/// segmentBlocked per sample. Throws penumbra::Error for an id out of range or non-finite input.
inline HardReference hardReference(const VisibilityOracle& oracle, const std::vector<glm::vec4>& positions,
                                   const std::vector<uint32_t>& ids, const HardLight& light,
                                   const VisibilityOptions& options = {}) {
    HardReference ref;
    ref.ids = ids;
    ref.receivers.reserve(ids.size());
    for (size_t i = 0; i < ids.size(); ++i) {
        PENUMBRA_CHECK(ids[i] < positions.size(), "penumbra::reference::hardReference: ids[", i, "] = ", ids[i],
                       " is out of range (", positions.size(), " positions)");
        ref.receivers.emplace_back(glm::vec3(positions[ids[i]]));
    }
    ref.blocked.assign(ids.size(), 0);
    ref.tie.assign(ids.size(), 0);
    ref.light_ends.resize(ids.size());
    if (!light.directional) {
        const VisibilityResult result = oracle.evaluate(ref.receivers, {light.position}, options);
        for (size_t r = 0; r < ids.size(); ++r) {
            ref.blocked[r] = result.isBlocked(r, 0);
            ref.tie[r] = result.isTie(r, 0);
            ref.light_ends[r] = light.position;
        }
    } else {
        for (size_t r = 0; r < ids.size(); ++r) {
            ref.light_ends[r] = ref.receivers[r] + light.direction * light.reach;
            bool tie = false;
            ref.blocked[r] = oracle.segmentBlocked(ref.receivers[r], ref.light_ends[r], options, &tie);
            ref.tie[r] = tie;
        }
    }
    return ref;
}

namespace detail {

inline void countHardStates(const std::vector<uint32_t>& states, HardComparison& c) {
    for (uint32_t state : states) {
        if (state == PENUMBRA_AFH_BACK_FACING) ++c.back_facing;
        else if (state == PENUMBRA_AFH_NO_SAMPLE) ++c.no_sample;
        else if (state == PENUMBRA_AFH_UNTESTED) ++c.untested;
        else if (state != PENUMBRA_AFH_LIT && state != PENUMBRA_AFH_SHADOWED) ++c.other_state;
    }
}

}  // namespace detail

/// A method's states (one per sample id) against prepared oracle verdicts (two-step form).
/// `oracle` (optional) fills HardMismatch::crossing. Throws when a reference id is outside states.
inline HardComparison compareHardStates(const HardReference& reference, const std::vector<uint32_t>& states,
                                        size_t max_reported = 8, const VisibilityOracle* oracle = nullptr) {
    HardComparison c;
    detail::countHardStates(states, c);
    c.samples = reference.ids.size();
    for (size_t r = 0; r < reference.ids.size(); ++r) {
        const uint32_t id = reference.ids[r];
        PENUMBRA_CHECK(id < states.size(), "penumbra::reference::compareHardStates: sample ", id,
                       " is outside the ", states.size(), " states");
        const uint32_t state = states[id];
        const bool shadowed = state == PENUMBRA_AFH_SHADOWED;
        c.undecided += state != PENUMBRA_AFH_LIT && !shadowed;
        c.shadowed += shadowed;
        c.blocked += reference.blocked[r] != 0;
        if (reference.tie[r]) {
            ++c.ties;
            continue;
        }
        if (shadowed == (reference.blocked[r] != 0)) continue;
        ++c.mismatched;
        if (c.first_mismatches.size() < max_reported) {
            HardMismatch m;
            m.sample = id;
            m.position = reference.receivers[r];
            m.light_end = reference.light_ends[r];
            m.shadowed = shadowed;
            m.blocked = reference.blocked[r] != 0;
            if (oracle && m.light_end != m.position) m.crossing = oracle->closestHit(m.position, m.light_end - m.position, 0.0, 1.0);
            c.first_mismatches.push_back(m);
        }
    }
    return c;
}

/// One step: the samples `states` marks LIT or SHADOWED, at `positions` (one vec4 per sample id,
/// the very floats the method used), against the oracle with `options` (set coplanar_epsilon to
/// the method's). Mismatch reports include the oracle's first crossing.
inline HardComparison compareHardStates(const VisibilityOracle& oracle, const std::vector<glm::vec4>& positions,
                                        const std::vector<uint32_t>& states, const HardLight& light,
                                        const VisibilityOptions& options = {}, size_t max_reported = 8) {
    PENUMBRA_CHECK(positions.size() >= states.size(), "penumbra::reference::compareHardStates: ", states.size(),
                   " states but only ", positions.size(), " positions");
    const HardReference reference = hardReference(oracle, positions, testedSamples(states), light, options);
    return compareHardStates(reference, states, max_reported, &oracle);
}

}  // namespace reference
}  // namespace penumbra

#endif
