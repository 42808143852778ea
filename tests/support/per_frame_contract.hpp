// Test helper: the per-frame contract check (docs/design.md convention 2) of one call — run it under
// a GL audit and an allocation counter and check that it made GL calls but no query, glGetError,
// read-back, map or sync wait, and no heap allocation on the calling thread outside GL calls (the
// driver's own allocations inside them are its business: support/driver_call.hpp). Includes
// support/alloc_counter.hpp, so the same rule holds: one translation unit per executable.
#ifndef PENUMBRA_TESTS_SUPPORT_PER_FRAME_CONTRACT_HPP
#define PENUMBRA_TESTS_SUPPORT_PER_FRAME_CONTRACT_HPP

#include "support/alloc_counter.hpp"
#include "support/gl_audit.hpp"

#include <doctest/doctest.h>

#include <cstddef>

namespace penumbra::test {

/// Runs frame() once under the audit and checks the contract; returns the GL calls it made.
template <typename Frame>
size_t checkPerFrameContract(Frame&& frame) {
    GlAudit audit;  // allocates its log here, before counting starts
    AllocationCounter heap;
    audit.start();
    heap.start();
    frame();  // no doctest macros inside: they allocate
    heap.stop();
    audit.stop();
    INFO(audit.report());
    INFO("heap: ", heap.allocations(), " allocations by the call, ", heap.driverAllocations(),
         " inside GL calls (the driver's, allowed)");
    CHECK(audit.calls() > 0);
    CHECK(audit.queries() == 0);
    CHECK(audit.errorChecks() == 0);
    CHECK(audit.readBacks() == 0);
    CHECK(audit.maps() == 0);
    CHECK(audit.syncWaits() == 0);
    CHECK(heap.allocations() == 0);
    return audit.calls();
}

}  // namespace penumbra::test

#endif
