// penumbra — an opt-in GL state snapshot for integrators who want every binding a block touches
// put back. Blocks themselves never restore state (the integrator owns it, STYLE.md habit 16);
// each executor's header lists exactly what it changes. StateSave queries GL (glGet*) when
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
        for (size_t e = 0; e < kEnables.size(); ++e) enabled_[e] = glIsEnabled(kEnables[e]);
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
        for (size_t e = 0; e < kEnables.size(); ++e) {
            if (enabled_[e]) glEnable(kEnables[e]);
            else glDisable(kEnables[e]);
        }
    }

private:
    struct Indexed {
        GLint buffer = 0;
        GLint64 start = 0, size = 0;
    };
    static constexpr std::array<GLenum, 6> kEnables = {GL_DEPTH_TEST, GL_CULL_FACE, GL_DEPTH_CLAMP,
                                                       GL_RASTERIZER_DISCARD, GL_STENCIL_TEST, GL_BLEND};
    GLint program_ = 0, draw_framebuffer_ = 0, read_framebuffer_ = 0, vertex_array_ = 0;
    GLint generic_ssbo_ = 0, generic_ubo_ = 0, draw_indirect_ = 0, dispatch_indirect_ = 0, active_texture_ = 0;
    std::array<GLint, 4> viewport_{};
    std::array<Indexed, kBindings> ssbo_{}, ubo_{};
    std::array<GLint, kTextureUnits> textures_{}, samplers_{};
    std::array<GLboolean, kEnables.size()> enabled_{};

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
