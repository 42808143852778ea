// penumbra — an opt-in GL state snapshot for integrators who want every binding a block touches
// put back: program, framebuffers, vertex array, viewport, buffer bindings (generic, indirect, the
// first 16 indexed SSBO / UBO ones), texture and sampler units 0-7, image units 0-7, the enables
// and rasterizer state blocks set (gl::setPassRasterState: scissor test, polygon mode, clip
// distances 0-7, clip control, depth range, smoothing, offset, primitive restart, front face,
// provoking vertex), draw buffer 0's blending and colour mask, and the stencil function, operations
// and write masks of both faces. Blocks themselves never restore
// state (the integrator owns it, STYLE.md habit 16); each executor's header lists exactly what it
// changes. StateSave queries GL (glGet*) when
// constructed, so it belongs around calls where that cost is acceptable, not in tight frames on
// drivers where queries stall.
//
//   {
//       penumbra::gl::StateSave saved;   // snapshot
//       scanner.scan(...);               // block changes program, SSBO bindings, ...
//   }                                    // destructor restores the snapshot
#ifndef PENUMBRA_GL_STATE_HPP
#define PENUMBRA_GL_STATE_HPP

#include "penumbra/gl/gl.hpp"

#include <array>

namespace penumbra::gl {

class StateSave {
public:
    /// Indexed bindings saved per target (GL 4.5 guarantees at least 8 SSBO and 36 UBO bindings).
    static constexpr int kBindings = 16;
    static constexpr int kTextureUnits = 8;
    static constexpr int kImageUnits = 8;  ///< GL 4.5 guarantees 8 image units

    StateSave() {
        glGetIntegerv(GL_CURRENT_PROGRAM, &program_);
        glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw_framebuffer_);
        glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &read_framebuffer_);
        glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &vertex_array_);
        glGetIntegerv(GL_VIEWPORT, viewport_.data());
        glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic_ssbo_);
        glGetIntegerv(GL_UNIFORM_BUFFER_BINDING, &generic_ubo_);
        glGetIntegerv(GL_DRAW_INDIRECT_BUFFER_BINDING, &draw_indirect_);
        glGetIntegerv(GL_DISPATCH_INDIRECT_BUFFER_BINDING, &dispatch_indirect_);
        glGetIntegerv(GL_ACTIVE_TEXTURE, &active_texture_);
        for (int i = 0; i < kBindings; ++i) {
            save(GL_SHADER_STORAGE_BUFFER_BINDING, GL_SHADER_STORAGE_BUFFER_START, GL_SHADER_STORAGE_BUFFER_SIZE, i,
                 ssbo_[i]);
            save(GL_UNIFORM_BUFFER_BINDING, GL_UNIFORM_BUFFER_START, GL_UNIFORM_BUFFER_SIZE, i, ubo_[i]);
        }
        for (int u = 0; u < kTextureUnits; ++u) {
            glActiveTexture(GL_TEXTURE0 + u);
            glGetIntegerv(GL_TEXTURE_BINDING_2D, &textures_[u]);
            glGetIntegerv(GL_SAMPLER_BINDING, &samplers_[u]);
        }
        glActiveTexture(static_cast<GLenum>(active_texture_));
        for (int u = 0; u < kImageUnits; ++u) {
            ImageUnit& image = images_[u];
            const GLuint i = static_cast<GLuint>(u);
            glGetIntegeri_v(GL_IMAGE_BINDING_NAME, i, &image.texture);
            glGetIntegeri_v(GL_IMAGE_BINDING_LEVEL, i, &image.level);
            glGetIntegeri_v(GL_IMAGE_BINDING_LAYERED, i, &image.layered);
            glGetIntegeri_v(GL_IMAGE_BINDING_LAYER, i, &image.layer);
            glGetIntegeri_v(GL_IMAGE_BINDING_ACCESS, i, &image.access);
            glGetIntegeri_v(GL_IMAGE_BINDING_FORMAT, i, &image.format);
        }
        for (size_t e = 0; e < kEnables.size(); ++e) enabled_[e] = glIsEnabled(kEnables[e]);
        // Rasterizer state (gl::setPassRasterState) and draw buffer 0's blending and colour mask.
        glGetIntegerv(GL_POLYGON_MODE, polygon_mode_.data());
        glGetIntegerv(GL_CLIP_ORIGIN, &clip_origin_);
        glGetIntegerv(GL_CLIP_DEPTH_MODE, &clip_depth_mode_);
        glGetDoublev(GL_DEPTH_RANGE, depth_range_.data());
        glGetIntegerv(GL_FRONT_FACE, &front_face_);
        glGetIntegerv(GL_PROVOKING_VERTEX, &provoking_vertex_);
        blend0_ = glIsEnabledi(GL_BLEND, 0);
        const GLenum blend_names[6] = {GL_BLEND_SRC_RGB, GL_BLEND_DST_RGB, GL_BLEND_SRC_ALPHA, GL_BLEND_DST_ALPHA,
                                       GL_BLEND_EQUATION_RGB, GL_BLEND_EQUATION_ALPHA};
        for (int b = 0; b < 6; ++b) glGetIntegeri_v(blend_names[b], 0, &blend_state_[b]);
        glGetBooleani_v(GL_COLOR_WRITEMASK, 0, color_mask0_.data());
        const GLenum stencil_names[2][6] = {
            {GL_STENCIL_FUNC, GL_STENCIL_REF, GL_STENCIL_VALUE_MASK, GL_STENCIL_FAIL, GL_STENCIL_PASS_DEPTH_FAIL,
             GL_STENCIL_PASS_DEPTH_PASS},
            {GL_STENCIL_BACK_FUNC, GL_STENCIL_BACK_REF, GL_STENCIL_BACK_VALUE_MASK, GL_STENCIL_BACK_FAIL,
             GL_STENCIL_BACK_PASS_DEPTH_FAIL, GL_STENCIL_BACK_PASS_DEPTH_PASS}};
        for (int f = 0; f < 2; ++f)
            for (int k = 0; k < 6; ++k) glGetIntegerv(stencil_names[f][k], &stencil_[f][k]);
        glGetIntegerv(GL_STENCIL_WRITEMASK, &stencil_writemask_[0]);
        glGetIntegerv(GL_STENCIL_BACK_WRITEMASK, &stencil_writemask_[1]);
    }
    StateSave(const StateSave&) = delete;
    StateSave& operator=(const StateSave&) = delete;
    ~StateSave() {
        glUseProgram(static_cast<GLuint>(program_));
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(draw_framebuffer_));
        glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(read_framebuffer_));
        glBindVertexArray(static_cast<GLuint>(vertex_array_));
        glViewport(viewport_[0], viewport_[1], viewport_[2], viewport_[3]);
        for (int i = 0; i < kBindings; ++i) {
            restore(GL_SHADER_STORAGE_BUFFER, i, ssbo_[i]);
            restore(GL_UNIFORM_BUFFER, i, ubo_[i]);
        }
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(generic_ssbo_));
        glBindBuffer(GL_UNIFORM_BUFFER, static_cast<GLuint>(generic_ubo_));
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, static_cast<GLuint>(draw_indirect_));
        glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, static_cast<GLuint>(dispatch_indirect_));
        for (int u = 0; u < kTextureUnits; ++u) {
            glBindTextureUnit(static_cast<GLuint>(u), static_cast<GLuint>(textures_[u]));
            glBindSampler(static_cast<GLuint>(u), static_cast<GLuint>(samplers_[u]));
        }
        glActiveTexture(static_cast<GLenum>(active_texture_));
        for (int u = 0; u < kImageUnits; ++u) {
            const ImageUnit& image = images_[u];
            glBindImageTexture(static_cast<GLuint>(u), static_cast<GLuint>(image.texture), image.level,
                               image.layered ? GL_TRUE : GL_FALSE, image.layer, static_cast<GLenum>(image.access),
                               static_cast<GLenum>(image.format));
        }
        for (size_t e = 0; e < kEnables.size(); ++e) {
            if (enabled_[e]) glEnable(kEnables[e]);
            else glDisable(kEnables[e]);
        }
        glPolygonMode(GL_FRONT_AND_BACK, static_cast<GLenum>(polygon_mode_[0]));
        glClipControl(static_cast<GLenum>(clip_origin_), static_cast<GLenum>(clip_depth_mode_));
        glDepthRange(depth_range_[0], depth_range_[1]);
        glFrontFace(static_cast<GLenum>(front_face_));
        glProvokingVertex(static_cast<GLenum>(provoking_vertex_));
        if (blend0_) glEnablei(GL_BLEND, 0);
        else glDisablei(GL_BLEND, 0);
        glBlendFuncSeparatei(0, static_cast<GLenum>(blend_state_[0]), static_cast<GLenum>(blend_state_[1]),
                             static_cast<GLenum>(blend_state_[2]), static_cast<GLenum>(blend_state_[3]));
        glBlendEquationSeparatei(0, static_cast<GLenum>(blend_state_[4]), static_cast<GLenum>(blend_state_[5]));
        glColorMaski(0, color_mask0_[0], color_mask0_[1], color_mask0_[2], color_mask0_[3]);
        for (int f = 0; f < 2; ++f) {
            const GLenum face = f == 0 ? GL_FRONT : GL_BACK;
            const GLint* s = stencil_[f].data();
            glStencilFuncSeparate(face, static_cast<GLenum>(s[0]), s[1], static_cast<GLuint>(s[2]));
            glStencilOpSeparate(face, static_cast<GLenum>(s[3]), static_cast<GLenum>(s[4]), static_cast<GLenum>(s[5]));
            glStencilMaskSeparate(face, static_cast<GLuint>(stencil_writemask_[f]));
        }
    }

private:
    struct Indexed {
        GLint buffer = 0;
        GLint64 start = 0, size = 0;
    };
    struct ImageUnit {
        GLint texture = 0, level = 0, layered = 0, layer = 0, access = GL_READ_ONLY, format = GL_R8;
    };
    static constexpr std::array<GLenum, 19> kEnables = {
        GL_DEPTH_TEST,       GL_CULL_FACE,          GL_DEPTH_CLAMP,         GL_RASTERIZER_DISCARD,
        GL_STENCIL_TEST,     GL_SCISSOR_TEST,       GL_POLYGON_SMOOTH,      GL_POLYGON_OFFSET_FILL,
        GL_PRIMITIVE_RESTART, GL_PRIMITIVE_RESTART_FIXED_INDEX, GL_CLIP_DISTANCE0, GL_CLIP_DISTANCE0 + 1,
        GL_CLIP_DISTANCE0 + 2, GL_CLIP_DISTANCE0 + 3, GL_CLIP_DISTANCE0 + 4, GL_CLIP_DISTANCE0 + 5,
        GL_CLIP_DISTANCE0 + 6, GL_CLIP_DISTANCE0 + 7, GL_BLEND};  // GL_BLEND last: draw buffer 0 is redone below
    GLint program_ = 0, draw_framebuffer_ = 0, read_framebuffer_ = 0, vertex_array_ = 0;
    GLint generic_ssbo_ = 0, generic_ubo_ = 0, draw_indirect_ = 0, dispatch_indirect_ = 0, active_texture_ = 0;
    std::array<GLint, 4> viewport_{};
    std::array<Indexed, kBindings> ssbo_{}, ubo_{};
    std::array<GLint, kTextureUnits> textures_{}, samplers_{};
    std::array<GLboolean, kEnables.size()> enabled_{};
    std::array<ImageUnit, kImageUnits> images_{};
    std::array<GLint, 2> polygon_mode_{GL_FILL, GL_FILL};
    GLint clip_origin_ = GL_LOWER_LEFT, clip_depth_mode_ = GL_NEGATIVE_ONE_TO_ONE;
    std::array<GLdouble, 2> depth_range_{0.0, 1.0};
    GLint front_face_ = GL_CCW, provoking_vertex_ = GL_LAST_VERTEX_CONVENTION;
    GLboolean blend0_ = GL_FALSE;
    std::array<GLint, 6> blend_state_{};
    std::array<GLboolean, 4> color_mask0_{GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE};
    std::array<std::array<GLint, 6>, 2> stencil_{};  // front, back: func, ref, value mask, fail, zfail, zpass
    std::array<GLint, 2> stencil_writemask_{};

    static void save(GLenum binding, GLenum start, GLenum size, int i, Indexed& out) {
        glGetIntegeri_v(binding, static_cast<GLuint>(i), &out.buffer);
        glGetInteger64i_v(start, static_cast<GLuint>(i), &out.start);
        glGetInteger64i_v(size, static_cast<GLuint>(i), &out.size);
    }
    static void restore(GLenum target, int i, const Indexed& in) {
        if (in.buffer != 0 && in.size > 0) {
            glBindBufferRange(target, static_cast<GLuint>(i), static_cast<GLuint>(in.buffer),
                              static_cast<GLintptr>(in.start), static_cast<GLsizeiptr>(in.size));
        } else {
            glBindBufferBase(target, static_cast<GLuint>(i), static_cast<GLuint>(in.buffer));
        }
    }
};

}  // namespace penumbra::gl

#endif
