// penumbra — the one place library headers get GL declarations from.
//
// Integration: penumbra never ships a GL loader of its own. Define PENUMBRA_GL_HEADER to your
// engine's loader header (a string or <...> token) before including any penumbra GL header;
// the default is glad 2's <glad/gl.h>. Whatever header you name must declare the GL 4.5 core
// entry points and enums.
#ifndef PENUMBRA_GL_GL_HPP
#define PENUMBRA_GL_GL_HPP

#ifndef PENUMBRA_GL_HEADER
#define PENUMBRA_GL_HEADER <glad/gl.h>
#endif
#include PENUMBRA_GL_HEADER

#include "penumbra/error.hpp"

#include <string>

namespace penumbra::gl {

/// Name of a GL error code, for messages.
inline const char* errorName(GLenum code) {
    switch (code) {
        case GL_NO_ERROR: return "GL_NO_ERROR";
        case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
        case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
        case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
        case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
        case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
        case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
        case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
        default: return "unknown GL error";
    }
}

/// Drains the GL error queue; throws penumbra::Error naming `where` and the first error seen.
/// Setup paths call it after object creation; hot paths never do.
inline void checkErrors(const char* where) {
    GLenum first = GL_NO_ERROR;
    for (GLenum code = glGetError(); code != GL_NO_ERROR; code = glGetError()) {
        if (first == GL_NO_ERROR) first = code;
    }
    PENUMBRA_CHECK(first == GL_NO_ERROR, "penumbra: ", errorName(first), " after ", where);
}

/// glGetIntegerv as a value.
inline GLint getInteger(GLenum name) {
    GLint value = 0;
    glGetIntegerv(name, &value);
    return value;
}

/// glGetInteger64v as a value.
inline GLint64 getInteger64(GLenum name) {
    GLint64 value = 0;
    glGetInteger64v(name, &value);
    return value;
}

/// glGetIntegeri_v as a value.
inline GLint getInteger(GLenum name, GLuint index) {
    GLint value = 0;
    glGetIntegeri_v(name, index, &value);
    return value;
}

/// glDeleteBuffers that leaves the engine's generic GL_SHADER_STORAGE_BUFFER, GL_UNIFORM_BUFFER and
/// GL_ATOMIC_COUNTER_BUFFER bindings as GL 4.5 §5.1.2 says: reset only where they named a deleted
/// buffer. Mesa unbinds a deleted buffer's indexed points through the calls that also set the
/// generic binding, zeroing it. Queries GL (three glGetIntegerv): setup and destructors only.
inline void deleteBuffers(GLsizei count, const GLuint* buffers) {
    static constexpr GLenum kTargets[3][2] = {{GL_SHADER_STORAGE_BUFFER, GL_SHADER_STORAGE_BUFFER_BINDING},
                                              {GL_UNIFORM_BUFFER, GL_UNIFORM_BUFFER_BINDING},
                                              {GL_ATOMIC_COUNTER_BUFFER, GL_ATOMIC_COUNTER_BUFFER_BINDING}};
    GLint generic[3];
    for (int t = 0; t < 3; ++t) generic[t] = getInteger(kTargets[t][1]);
    glDeleteBuffers(count, buffers);
    for (int t = 0; t < 3; ++t) {
        bool deleted = generic[t] == 0;
        for (GLsizei i = 0; i < count && !deleted; ++i) deleted = static_cast<GLint>(buffers[i]) == generic[t];
        if (!deleted) glBindBuffer(kTargets[t][0], static_cast<GLuint>(generic[t]));
    }
}

/// The rasterizer state every penumbra draw pass relies on, set before it draws into its own
/// framebuffer whatever the engine left behind (a UI pass's scissor box, a wireframe debug
/// toggle, user clip planes, D3D-style clip control, primitive restart, a narrowed depth range):
/// scissor test off, polygon mode GL_FILL, GL_CLIP_DISTANCE0..7 off (GL 4.5 guarantees 8), clip
/// control (GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE), depth range [0, 1], polygon smoothing and
/// polygon offset (fill) off, both primitive restarts off, front face GL_CCW, provoking vertex
/// GL_LAST_VERTEX_CONVENTION. Changed, not restored (each block's "GL state" lists it); a dozen
/// state calls, no query. tests/engine_state_test.cpp runs every drawing block under the opposite
/// state and requires the same results bit for bit.
inline void setPassRasterState() {
    glDisable(GL_SCISSOR_TEST);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    for (GLenum i = 0; i < 8; ++i) glDisable(GL_CLIP_DISTANCE0 + i);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    glDepthRange(0.0, 1.0);
    glDisable(GL_POLYGON_SMOOTH);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_PRIMITIVE_RESTART);
    glDisable(GL_PRIMITIVE_RESTART_FIXED_INDEX);
    glFrontFace(GL_CCW);
    glProvokingVertex(GL_LAST_VERTEX_CONVENTION);
}

/// Which list blocks does the longest list need (the list-walking light passes: AliasFreeHard-
/// and SampleBasedSoftShadows)? With the caller's block-predicate program, empty VAO, parameters
/// and list header bound: per block b < `blocks` one point (vertex b) under the occlusion query
/// `queries[b]` (any samples passed: some list reaches block b; the light pass of block b then
/// renders under that query's condition). The points go through a 1 x 1 viewport, which puts each
/// point (NDC origin) on pixel (0, 0)'s centre: in the grid's own viewport it would sit on a pixel
/// corner whenever W and H are even, and whether a 1-pixel point there covers any pixel centre is
/// the rasteriser's tie rule (no fragment would skip every light-pass block). Leaves the viewport
/// at the grid's `width` x `height`.
template <class Queries>
inline void drawListBlockPredicates(const Queries& queries, uint32_t blocks, uint32_t width, uint32_t height) {
    glViewport(0, 0, 1, 1);
    for (uint32_t b = 0; b < blocks; ++b) {
        glBeginQuery(GL_ANY_SAMPLES_PASSED, queries[b].id());
        glDrawArrays(GL_POINTS, static_cast<GLint>(b), 1);
        glEndQuery(GL_ANY_SAMPLES_PASSED);
    }
    glViewport(0, 0, static_cast<GLsizei>(width), static_cast<GLsizei>(height));
}

/// The occupancy stencil of the list-walking light passes (AliasFreeHardOptions::
/// skip_empty_texels, SoftSkips::empty_blocks) holds 8 bits per texel: blocks from this one on
/// are drawn without it.
inline constexpr uint32_t kOccupancyStencilBlocks = 255;

/// Fills `framebuffer`'s stencil (bound for drawing, viewport the grid) with each texel's count of
/// non-empty list blocks: cleared to 0, then per block b < min(blocks, kOccupancyStencilBlocks) a
/// full-screen triangle of `program` (whose fragments survive where block b holds samples) with
/// GL_INCR, after `bind_block(b)` (the caller's parameters of block b) and under the condition of
/// `queries[b]` (drawListBlockPredicates: blocks no list needs draw nothing). Leaves
/// GL_STENCIL_TEST on, write mask 0, operations GL_KEEP; `program` and `vao` bound.
template <class Queries, class BindBlock>
inline void drawOccupancyStencil(GLuint framebuffer, GLuint program, GLuint vao, const Queries& queries, uint32_t blocks,
                                 BindBlock&& bind_block) {
    glStencilMask(0xFFu);
    const GLint clear = 0;
    glClearNamedFramebufferiv(framebuffer, GL_STENCIL, 0, &clear);
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_ALWAYS, 0, 0xFFu);
    glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
    glUseProgram(program);
    glBindVertexArray(vao);
    for (uint32_t b = 0; b < blocks && b < kOccupancyStencilBlocks; ++b) {
        glBeginConditionalRender(queries[b].id(), GL_QUERY_WAIT);
        bind_block(b);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glEndConditionalRender();
    }
    glStencilMask(0u);
    glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
}

/// The light pass of block b under the occupancy stencil: stencil test `func` against b where the
/// stencil counts that block (`enabled` and b < kOccupancyStencilBlocks), else no stencil test.
inline void occupancyStencilTest(bool enabled, uint32_t b, GLenum func) {
    if (enabled && b < kOccupancyStencilBlocks) {
        glEnable(GL_STENCIL_TEST);
        glStencilFunc(func, static_cast<GLint>(b), 0xFFu);
    } else {
        glDisable(GL_STENCIL_TEST);
    }
}

}  // namespace penumbra::gl

#endif
