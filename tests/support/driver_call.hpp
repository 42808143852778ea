// Whether the calling thread is inside a GL driver call: support/gl_audit.hpp's glad pre-call
// callback enters, its post-call callback leaves. support/alloc_counter.hpp reads it to tell the
// driver's operator new calls (NVIDIA's driver allocates through the program's global operator
// new inside glDispatchCompute, glDrawArrays ...) from the calls of penumbra's own code, which the
// per-frame contract forbids. Programs without support/gl_audit.hpp never enter: every allocation
// is then their own.
#ifndef PENUMBRA_TESTS_SUPPORT_DRIVER_CALL_HPP
#define PENUMBRA_TESTS_SUPPORT_DRIVER_CALL_HPP

namespace penumbra::test::detail {

/// GL calls in progress on this thread (glad's debug wrappers: pre-call ... post-call).
inline thread_local int t_driver_call_depth = 0;

inline void enterDriverCall() { ++t_driver_call_depth; }
inline void leaveDriverCall() {
    if (t_driver_call_depth > 0) --t_driver_call_depth;
}
inline bool insideDriverCall() { return t_driver_call_depth > 0; }

}  // namespace penumbra::test::detail

#endif
