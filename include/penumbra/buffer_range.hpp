// penumbra — the per-frame conventions every block's executor follows (STYLE.md habits 15-16),
// in plain C++ with no GL header, so pure setup and plans can name buffers too.
//
//   * BufferRange: a part of a buffer object the integrator owns (name, byte offset, byte size).
//     Executors take ranges wherever they read or write the integrator's memory; they never ask
//     GL how large a buffer is in the per-frame call. The ranges' sizes are the integrator's
//     word; the load-time `validate...` functions (penumbra/gl/validate.hpp) check them against
//     GL_BUFFER_SIZE once.
//   * Status: what a per-frame call returns. A per-frame call allocates nothing, queries nothing
//     (glGet*, glIs*, glGetError), reads nothing back and throws nothing: misuse it could detect
//     without GL (a range too small for what reserve() sized, a size larger than reserved)
//     returns a Status other than Ok after PENUMBRA_ASSERT, and issues no GL call at all.
#ifndef PENUMBRA_BUFFER_RANGE_HPP
#define PENUMBRA_BUFFER_RANGE_HPP

#include <cstdint>

namespace penumbra {

/// A byte range of a GL buffer object (name as GLuint, which is a 32-bit unsigned int).
/// `size` 0 means "empty": executors never bind an empty range.
struct BufferRange {
    uint32_t buffer = 0;  ///< GL buffer name
    uint64_t offset = 0;  ///< bytes from the buffer's start
    uint64_t size = 0;    ///< bytes

    constexpr bool empty() const { return size == 0; }
    /// At least `bytes` long (and non-null when bytes > 0).
    constexpr bool holds(uint64_t bytes) const { return bytes == 0 || (buffer != 0 && size >= bytes); }
    /// The sub-range [offset + first, offset + first + bytes).
    constexpr BufferRange sub(uint64_t first, uint64_t bytes) const { return {buffer, offset + first, bytes}; }
};

/// Result of a per-frame call (see the file comment). Only Ok did any GPU work.
enum class Status : uint32_t {
    Ok = 0,
    NotReserved,     ///< reserve() was not called, or for a smaller size than this call needs
    RangeTooSmall,   ///< a BufferRange is shorter than the call needs (or null)
    Misaligned,      ///< a BufferRange offset breaks the alignment the call needs
    InvalidArgument  ///< a count or option outside what setup accepted
};

inline const char* statusName(Status s) {
    switch (s) {
        case Status::Ok: return "ok";
        case Status::NotReserved: return "not reserved";
        case Status::RangeTooSmall: return "range too small";
        case Status::Misaligned: return "misaligned range";
        case Status::InvalidArgument: return "invalid argument";
    }
    return "unknown status";
}

}  // namespace penumbra

#endif
