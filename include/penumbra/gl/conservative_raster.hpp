// penumbra — GL helpers recording the Fixed-6 two-pass plan of penumbra/conservative_raster.hpp
// (sintorn2008 §3.2 at the seed's 6 geometry-shader output vertices; triangles that need clipping
// are spilled by the direct pass and drawn by an indirect spill pass).
//
// Integration summary
//   needs:    GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS >= 1 (checked by validateConservativeSpill);
//             a ConservativeRasterSetup with spill.enabled (Fixed6), a buffer range of at least
//             setup.spill.buffer_bytes you own (validate it once with validateConservativeSpill),
//             your two programs (direct: setup.spill.direct_defines, spill: setup.spill.spill_defines)
//             and the params block bound at your params binding.
//   per frame (no allocation, no query, no read-back, no exception):
//             beginConservativeSpill(setup, spill)   before the direct draw: writes setup.spill.reset
//                                                    into the header (glMemoryBarrier(BUFFER_UPDATE),
//                                                    glNamedBufferSubData, 32 bytes)
//                                                    and binds the range as SSBO `bindings.spill`;
//             ... your direct draw (glDrawArrays/Elements with the direct program) ...
//             drawConservativeSpill(setup, spill)    with the spill program current and any vertex
//                                                    array bound: glMemoryBarrier(SHADER_STORAGE |
//                                                    COMMAND), binds the range as SSBO and as
//                                                    GL_DRAW_INDIRECT_BUFFER, glDrawArraysIndirect.
//   changes:  the indexed SSBO binding `bindings.spill` and the GL_DRAW_INDIRECT_BUFFER binding;
//             nothing is unbound or restored (use gl::StateSave if you want that).
//   returns:  Status::InvalidArgument when the setup has no plan (Exact), RangeTooSmall when the
//             range is shorter than setup.spill.buffer_bytes, Misaligned when its offset is not a
//             multiple of 4 (GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT is checked at load time);
//             no GL call is made then.
//   optional: readConservativeSpillHeader() — a read-back for tests/statistics (not per frame).
#ifndef PENUMBRA_GL_CONSERVATIVE_RASTER_HPP
#define PENUMBRA_GL_CONSERVATIVE_RASTER_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/conservative_raster.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/validate.hpp"

#include <cstdint>

namespace penumbra::gl {

/// Binding points of the conservative-raster entries (defaults from conservative_raster_shared.h).
struct ConservativeRasterBindings {
    GLuint params = PENUMBRA_CONSERVATIVE_PARAMS_BINDING;  ///< std140 PenumbraConservativeParams
    GLuint spill = PENUMBRA_CONSERVATIVE_SPILL_BINDING;    ///< std430 spill header + triangles
};

namespace detail {
inline Status conservativeSpillStatus(const ConservativeRasterSetup& setup, const BufferRange& spill) {
    if (!setup.spill.enabled) return Status::InvalidArgument;
    if (!spill.holds(setup.spill.buffer_bytes)) return Status::RangeTooSmall;
    if (spill.offset % 4u != 0) return Status::Misaligned;
    return Status::Ok;
}
}  // namespace detail

/// Load time: the range exists, fits its buffer, is aligned for an SSBO binding and holds the
/// plan's buffer_bytes. Throws penumbra::Error naming the problem. Queries GL.
inline void validateConservativeSpill(const ConservativeRasterSetup& setup, const BufferRange& spill) {
    PENUMBRA_CHECK(setup.spill.enabled, "penumbra::validateConservativeSpill: the setup has no spill plan (variant ",
                   conservativeVariantName(setup.options.variant), "; only fixed6 has one)");
    // The direct pass appends from the geometry stage: GL 4.3+ only requires 0 geometry-stage
    // storage blocks (desktop drivers have 8..16; llvmpipe 16).
    GLint geometry_blocks = 0;
    glGetIntegerv(GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS, &geometry_blocks);
    PENUMBRA_CHECK(geometry_blocks >= 1, "penumbra::validateConservativeSpill: GL_MAX_GEOMETRY_SHADER_STORAGE_BLOCKS = ",
                   geometry_blocks, ": the driver cannot write the spill buffer from the geometry stage");
    GLint alignment = 0;
    glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &alignment);
    validateRange(spill, setup.spill.buffer_bytes, "spill", "validateConservativeSpill",
                  static_cast<uint64_t>(alignment > 4 ? alignment : 4));
}

/// Per frame, before the direct draw (see the summary).
inline Status beginConservativeSpill(const ConservativeRasterSetup& setup, const BufferRange& spill,
                                     const ConservativeRasterBindings& bindings = {}) {
    const Status status = detail::conservativeSpillStatus(setup, spill);
    PENUMBRA_ASSERT(status == Status::Ok);
    if (status != Status::Ok) return status;
    // The last spill pass's shaders appended to this header: the reset is ordered after those
    // writes only by this bit (GL 4.5 §7.13.2).
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glNamedBufferSubData(spill.buffer, static_cast<GLintptr>(spill.offset + setup.spill.indirect_offset),
                         sizeof setup.spill.reset, &setup.spill.reset);
    bindRange(GL_SHADER_STORAGE_BUFFER, bindings.spill, spill.sub(0, setup.spill.buffer_bytes));
    return Status::Ok;
}

/// Per frame, after the direct draw, with the spill program current (see the summary).
inline Status drawConservativeSpill(const ConservativeRasterSetup& setup, const BufferRange& spill,
                                    const ConservativeRasterBindings& bindings = {}) {
    const Status status = detail::conservativeSpillStatus(setup, spill);
    PENUMBRA_ASSERT(status == Status::Ok);
    if (status != Status::Ok) return status;
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
    bindRange(GL_SHADER_STORAGE_BUFFER, bindings.spill, spill.sub(0, setup.spill.buffer_bytes));
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, spill.buffer);
    glDrawArraysIndirect(GL_TRIANGLES, reinterpret_cast<const void*>(
                                           static_cast<uintptr_t>(spill.offset + setup.spill.indirect_offset)));
    return Status::Ok;
}

/// The header after a frame (a synchronous read-back: tests and statistics only). Triangles the
/// direct pass spilled = count / 3 + overflow.
inline ConservativeSpillHeader readConservativeSpillHeader(const BufferRange& spill) {
    ConservativeSpillHeader header{};
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(spill.buffer, static_cast<GLintptr>(spill.offset), sizeof header, &header);
    return header;
}

}  // namespace penumbra::gl

#endif
