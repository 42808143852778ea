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

}  // namespace penumbra::gl

#endif
