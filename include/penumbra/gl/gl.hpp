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

/// glGetIntegeri_v as a value.
inline GLint getInteger(GLenum name, GLuint index) {
    GLint value = 0;
    glGetIntegeri_v(name, index, &value);
    return value;
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

}  // namespace penumbra::gl

#endif
