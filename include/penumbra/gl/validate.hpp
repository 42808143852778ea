// penumbra — load-time validation of the integrator's GL objects (queries allowed here, never in
// a per-frame call; see penumbra/buffer_range.hpp). Each check throws penumbra::Error naming the
// function, the role of the object and the offending value.
#ifndef PENUMBRA_GL_VALIDATE_HPP
#define PENUMBRA_GL_VALIDATE_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/error.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/pipelines/caster_class.hpp"

#include <cstdint>
#include <string>

namespace penumbra::gl {

/// `range` names a buffer object with storage, lies inside its GL_BUFFER_SIZE, has an offset
/// that is a multiple of `alignment`, and holds at least `min_bytes`. A range with
/// min_bytes == 0 and size 0 is accepted without any query.
inline void validateRange(const BufferRange& range, uint64_t min_bytes, const char* what, const char* function,
                          uint64_t alignment = 4) {
    if (min_bytes == 0 && range.size == 0) return;
    PENUMBRA_CHECK(range.buffer != 0 && glIsBuffer(range.buffer), "penumbra::", function, ": ", what, " buffer ",
                   range.buffer, " is not a buffer object");
    GLint64 size = 0;
    glGetNamedBufferParameteri64v(range.buffer, GL_BUFFER_SIZE, &size);
    PENUMBRA_CHECK(size > 0, "penumbra::", function, ": ", what, " buffer ", range.buffer,
                   " has no storage (GL_BUFFER_SIZE 0)");
    PENUMBRA_CHECK(alignment == 0 || range.offset % alignment == 0, "penumbra::", function, ": ", what, " offset ",
                   range.offset, " is not a multiple of ", alignment);
    const uint64_t total = static_cast<uint64_t>(size);
    PENUMBRA_CHECK(range.offset <= total && range.size <= total - range.offset, "penumbra::", function, ": ", what,
                   " range [", range.offset, ", +", range.size, ") exceeds buffer ", range.buffer,
                   "'s GL_BUFFER_SIZE ", total);
    PENUMBRA_CHECK(range.size >= min_bytes, "penumbra::", function, ": ", what, " range holds ", range.size,
                   " bytes, needs ", min_bytes);
}

/// The whole of buffer `buffer` as a range (one query: for setup code and tests).
inline BufferRange wholeBuffer(GLuint buffer) {
    GLint64 size = 0;
    if (buffer) glGetNamedBufferParameteri64v(buffer, GL_BUFFER_SIZE, &size);
    return {buffer, 0, static_cast<uint64_t>(size > 0 ? size : 0)};
}

// Indexed bindings go through the multi-bind calls (GL 4.4): glBindBufferBase / glBindBufferRange
// would also change the target's generic binding, which no header lists (README's contract).

/// Binds [offset, +size) of `buffer` at indexed `target` binding `index`; no query.
inline void bindRange(GLenum target, GLuint index, GLuint buffer, GLintptr offset, GLsizeiptr size) {
    glBindBuffersRange(target, index, 1, &buffer, &offset, &size);
}

/// Binds `range` at indexed `target` binding `index` (GL_SHADER_STORAGE_BUFFER,
/// GL_UNIFORM_BUFFER, ...). No query; an empty range binds nothing.
inline void bindRange(GLenum target, GLuint index, const BufferRange& range) {
    if (range.size == 0) return;
    bindRange(target, index, range.buffer, static_cast<GLintptr>(range.offset), static_cast<GLsizeiptr>(range.size));
}

/// Binds the whole of `buffer` at indexed `target` binding `index`; no query.
inline void bindBase(GLenum target, GLuint index, GLuint buffer) { glBindBuffersBase(target, index, 1, &buffer); }

/// One shader-storage block of an executor's program and the binding its Bindings struct gives it.
struct BlockBinding {
    const char* name;     ///< the Bindings struct's member (for messages)
    const char* block;    ///< the GLSL block name
    uint32_t binding;
};

/// Load time: every storage binding is below GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS and differs from
/// the others, the uniform binding is below GL_MAX_UNIFORM_BUFFER_BINDINGS; throws penumbra::Error
/// naming `bindings_struct`'s member.
inline void checkBlockBindings(const char* bindings_struct, const BlockBinding* storage, int count,
                               const char* uniform_name, uint32_t uniform_binding) {
    const GLint max_ssbo = getInteger(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
    const GLint max_ubo = getInteger(GL_MAX_UNIFORM_BUFFER_BINDINGS);
    for (int i = 0; i < count; ++i) {
        PENUMBRA_CHECK(storage[i].binding < static_cast<uint32_t>(max_ssbo), "penumbra: ", bindings_struct, "::",
                       storage[i].name, " ", storage[i].binding, " is not below GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS ",
                       max_ssbo);
        for (int j = 0; j < i; ++j) {
            PENUMBRA_CHECK(storage[i].binding != storage[j].binding, "penumbra: ", bindings_struct, "::", storage[i].name,
                           " and ", storage[j].name, " are both ", storage[i].binding,
                           " (the shader-storage bindings must differ)");
        }
    }
    PENUMBRA_CHECK(uniform_binding < static_cast<uint32_t>(max_ubo), "penumbra: ", bindings_struct, "::", uniform_name, " ",
                   uniform_binding, " is not below GL_MAX_UNIFORM_BUFFER_BINDINGS ", max_ubo);
}

/// Load time: re-points `program`'s storage blocks and its uniform block `uniform_block` at the
/// given bindings (program state, set once; blocks the program lacks are skipped).
inline void pointBlocks(GLuint program, const BlockBinding* storage, int count, const char* uniform_block,
                        uint32_t uniform_binding) {
    for (int i = 0; i < count; ++i) {
        const GLuint index = glGetProgramResourceIndex(program, GL_SHADER_STORAGE_BLOCK, storage[i].block);
        if (index != GL_INVALID_INDEX) glShaderStorageBlockBinding(program, index, storage[i].binding);
    }
    const GLuint block = glGetUniformBlockIndex(program, uniform_block);
    if (block != GL_INVALID_INDEX) glUniformBlockBinding(program, block, uniform_binding);
}

/// Load time: `count` caster ranges (CasterBuffer) against their buffers (GL queries; throws
/// naming `function` and the range): what checkCasterBuffers() checks per frame, plus the
/// buffers' sizes. Ranges of 0 triangles are skipped.
inline void validateCasterBuffers(const CasterBuffer* casters, uint32_t count, uint32_t ssbo_alignment, const char* function) {
    PENUMBRA_CHECK(count == 0 || casters != nullptr, "penumbra::", function, ": ", count, " ranges at a null pointer");
    for (uint32_t i = 0; i < count; ++i) {
        const CasterBuffer& c = casters[i];
        if (c.triangles == 0) continue;
        PENUMBRA_CHECK(c.stride >= 12 && c.stride % 4 == 0, "penumbra::", function, ": caster range ", i, ": stride ", c.stride,
                       " must be a multiple of 4, at least 12");
        PENUMBRA_CHECK(c.triangles <= kMaxCasterTriangles, "penumbra::", function, ": caster range ", i, ": ", c.triangles,
                       " triangles, at most ", kMaxCasterTriangles);
        PENUMBRA_CHECK(c.caster_class == CasterClass::Closed || c.caster_class == CasterClass::Open, "penumbra::", function,
                       ": caster range ", i, ": caster_class ", static_cast<int>(c.caster_class), " is neither Closed nor Open");
        const std::string what = "caster range " + std::to_string(i);
        validateRange(c.positions, casterPositionBytes(c), (what + " positions").c_str(), function, ssbo_alignment);
        if (!c.indices.empty()) validateRange(c.indices, uint64_t(c.triangles) * 12, (what + " indices").c_str(), function, ssbo_alignment);
    }
}

}  // namespace penumbra::gl

#endif
