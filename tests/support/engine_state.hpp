// The GL state an engine may leave behind when it calls a block in the middle of its frame, and
// GL's initial values of the same state (tests/engine_state_test.cpp, light_volume_gl_test.cpp).
#ifndef PENUMBRA_TESTS_SUPPORT_ENGINE_STATE_HPP
#define PENUMBRA_TESTS_SUPPORT_ENGINE_STATE_HPP

#include "penumbra/gl/gl.hpp"

#include <doctest/doctest.h>

#include <vector>

namespace penumbra::test {

/// State an engine may leave behind, all of it legal in a GL 4.5 core context.
inline void setHostileState() {
    glEnable(GL_SCISSOR_TEST);
    glScissor(1, 1, 1, 1);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    for (GLenum i = 0; i < 8; ++i) glEnable(GL_CLIP_DISTANCE0 + i);  // no penumbra shader writes them
    glClipControl(GL_UPPER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_POLYGON_SMOOTH);
    glEnable(GL_PRIMITIVE_RESTART);
    glPrimitiveRestartIndex(0);  // a real vertex index of every mesh
    glEnable(GL_PRIMITIVE_RESTART_FIXED_INDEX);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthRange(0.25, 0.5);
    glFrontFace(GL_CW);
    glProvokingVertex(GL_FIRST_VERTEX_CONVENTION);
    glPointSize(3.0f);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(4.0f, 16.0f);
    glEnable(GL_STENCIL_TEST);  // kills every fragment of a pass with a stencil buffer that kept it
    glStencilFunc(GL_NEVER, 7, 0x0Fu);
    glStencilOp(GL_ZERO, GL_INVERT, GL_DECR_WRAP);
    glStencilMask(0x3Cu);
    REQUIRE(glGetError() == GL_NO_ERROR);
}

/// Back to GL's initial values of everything setHostileState touched.
inline void setDefaultState() {
    glDisable(GL_SCISSOR_TEST);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    for (GLenum i = 0; i < 8; ++i) glDisable(GL_CLIP_DISTANCE0 + i);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
    glDisable(GL_POLYGON_SMOOTH);
    glDisable(GL_PRIMITIVE_RESTART);
    glPrimitiveRestartIndex(0);
    glDisable(GL_PRIMITIVE_RESTART_FIXED_INDEX);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthRange(0.0, 1.0);
    glFrontFace(GL_CCW);
    glProvokingVertex(GL_LAST_VERTEX_CONVENTION);
    glPointSize(1.0f);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(0.0f, 0.0f);
    glDisable(GL_STENCIL_TEST);
    glStencilFunc(GL_ALWAYS, 0, 0xFFFFFFFFu);
    glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
    glStencilMask(0xFFFFFFFFu);
    REQUIRE(glGetError() == GL_NO_ERROR);
}

/// The state setHostileState changes and blocks set, read back with glGet* (independently of
/// penumbra::gl::StateSave, whose restoring it checks), as one comparable list of numbers.
inline std::vector<double> rasterStateSnapshot() {
    std::vector<double> v;
    const GLenum enables[] = {GL_SCISSOR_TEST,    GL_POLYGON_SMOOTH,   GL_PRIMITIVE_RESTART, GL_PRIMITIVE_RESTART_FIXED_INDEX,
                              GL_POLYGON_OFFSET_FILL, GL_DEPTH_TEST,   GL_CULL_FACE,         GL_DEPTH_CLAMP,
                              GL_RASTERIZER_DISCARD, GL_STENCIL_TEST};
    for (GLenum e : enables) v.push_back(glIsEnabled(e));
    for (GLenum i = 0; i < 8; ++i) v.push_back(glIsEnabled(GL_CLIP_DISTANCE0 + i));
    v.push_back(glIsEnabledi(GL_BLEND, 0));
    const GLenum integers[] = {GL_CLIP_ORIGIN, GL_CLIP_DEPTH_MODE, GL_FRONT_FACE, GL_PROVOKING_VERTEX, GL_CURRENT_PROGRAM,
                               GL_DRAW_FRAMEBUFFER_BINDING, GL_VERTEX_ARRAY_BINDING, GL_PRIMITIVE_RESTART_INDEX,
                               GL_STENCIL_FUNC, GL_STENCIL_REF, GL_STENCIL_VALUE_MASK, GL_STENCIL_FAIL,
                               GL_STENCIL_PASS_DEPTH_FAIL, GL_STENCIL_PASS_DEPTH_PASS, GL_STENCIL_WRITEMASK,
                               GL_STENCIL_BACK_FUNC, GL_STENCIL_BACK_REF, GL_STENCIL_BACK_VALUE_MASK,
                               GL_STENCIL_BACK_FAIL, GL_STENCIL_BACK_PASS_DEPTH_FAIL, GL_STENCIL_BACK_PASS_DEPTH_PASS,
                               GL_STENCIL_BACK_WRITEMASK};
    for (GLenum name : integers) {
        GLint value = 0;
        glGetIntegerv(name, &value);
        v.push_back(value);
    }
    GLint polygon_mode[2] = {0, 0};
    glGetIntegerv(GL_POLYGON_MODE, polygon_mode);
    v.push_back(polygon_mode[0]);
    GLint viewport[4], scissor[4];
    glGetIntegerv(GL_VIEWPORT, viewport);
    glGetIntegerv(GL_SCISSOR_BOX, scissor);
    for (int i = 0; i < 4; ++i) v.push_back(viewport[i]), v.push_back(scissor[i]);
    GLdouble depth_range[2];
    glGetDoublev(GL_DEPTH_RANGE, depth_range);
    v.push_back(depth_range[0]);
    v.push_back(depth_range[1]);
    GLboolean mask[4];
    glGetBooleani_v(GL_COLOR_WRITEMASK, 0, mask);
    for (GLboolean b : mask) v.push_back(b);
    const GLenum blend[] = {GL_BLEND_SRC_RGB, GL_BLEND_DST_RGB, GL_BLEND_SRC_ALPHA, GL_BLEND_DST_ALPHA,
                            GL_BLEND_EQUATION_RGB, GL_BLEND_EQUATION_ALPHA};
    for (GLenum name : blend) {
        GLint value = 0;
        glGetIntegeri_v(name, 0, &value);
        v.push_back(value);
    }
    for (GLuint u = 0; u < 8; ++u) {
        GLint value = 0;
        glGetIntegeri_v(GL_IMAGE_BINDING_NAME, u, &value);
        v.push_back(value);
        glGetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, u, &value);
        v.push_back(value);
        glGetIntegeri_v(GL_UNIFORM_BUFFER_BINDING, u, &value);
        v.push_back(value);
    }
    return v;
}

}  // namespace penumbra::test

#endif
