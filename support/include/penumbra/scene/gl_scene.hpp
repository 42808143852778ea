// penumbra scene helpers on the GPU — what an engine already has and penumbra's tests, benchmarks
// and examples need: meshes in GL buffers and a G-buffer pass producing view samples.
// Part of penumbra::support (support/include/; a core install has none of it, see CMakeLists.txt:
// PENUMBRA_BUILD_SUPPORT). CMake target penumbra::support links tinyobjloader and stb.
//
// Integration summary
//   needs:    a current GL 4.5 context (PENUMBRA_GL_HEADER, see gl/gl.hpp); penumbra/scene/scene.hpp.
//   produces: GpuScene (one VAO of all meshes: attribute 0 = position, 1 = shading normal, an index
//             buffer, per-triangle face normals in an SSBO, per-mesh index ranges and `closed`
//             flags), GBuffer (world position, face normal + triangle id, shading normal, depth)
//             and the same data copied into SSBOs as view samples (one per pixel, row-major from
//             the bottom row, GL's convention; background pixels have position.w == 0).
//   shaders:  penumbra/scene/gbuffer.{vert,frag}.glsl, penumbra/scene/depth_only.vert.glsl.
#ifndef PENUMBRA_SCENE_GL_SCENE_HPP
#define PENUMBRA_SCENE_GL_SCENE_HPP

#include "penumbra/adjacency.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/pipelines/caster_class.hpp"
#include "penumbra/scene/scene.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <cstdint>
#include <vector>

namespace penumbra::scene {

/// One scene in GL buffers. Triangle ids are global across meshes, in mesh order.
class GpuScene {
public:
    struct Range {
        uint32_t first_index = 0;     ///< into the index buffer
        uint32_t index_count = 0;
        uint32_t first_triangle = 0;  ///< global triangle id of the first triangle
        bool closed = false;
    };

    explicit GpuScene(const Scene& scene) {
        std::vector<float> vertices;  // interleaved position (3) + normal (3)
        std::vector<uint32_t> indices;
        std::vector<glm::vec4> faces;
        for (const Mesh& mesh : scene.meshes) {
            const uint32_t base = static_cast<uint32_t>(vertices.size() / 6);
            Range r;
            r.first_index = static_cast<uint32_t>(indices.size());
            r.index_count = static_cast<uint32_t>(mesh.indices.size());
            r.first_triangle = static_cast<uint32_t>(faces.size());
            r.closed = mesh.closed;
            for (size_t v = 0; v < mesh.positions.size(); ++v) {
                const glm::vec3 n = v < mesh.normals.size() ? mesh.normals[v] : glm::vec3(0, 1, 0);
                const glm::vec3& p = mesh.positions[v];
                vertices.insert(vertices.end(), {p.x, p.y, p.z, n.x, n.y, n.z});
            }
            for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
                const glm::vec3 a = mesh.positions[mesh.indices[i]], b = mesh.positions[mesh.indices[i + 1]],
                                c = mesh.positions[mesh.indices[i + 2]];
                glm::vec3 n = glm::cross(b - a, c - a);
                const float len = glm::length(n);
                faces.emplace_back(len > 0 ? n / len : glm::vec3(0), mesh.closed ? 1.0f : 0.0f);
                for (int k = 0; k < 3; ++k) indices.push_back(base + mesh.indices[i + k]);
            }
            ranges_.push_back(r);
            positions_.insert(positions_.end(), mesh.positions.begin(), mesh.positions.end());
        }
        index_count_ = static_cast<uint32_t>(indices.size());
        cpu_indices_ = indices;
        vertices_ = gl::Buffer::fromVector(vertices);
        indices_ = gl::Buffer::fromVector(indices);
        face_normals_ = gl::Buffer::fromVector(faces);
        // The casters as buffers, one index buffer per class (meshes in order).
        for (int k = 0; k < 2; ++k) {
            std::vector<uint32_t> class_indices;
            for (const Range& r : ranges_)
                if (r.closed == (k == 0))
                    class_indices.insert(class_indices.end(), indices.begin() + r.first_index,
                                         indices.begin() + r.first_index + r.index_count);
            if (class_indices.empty()) continue;
            class_indices_[k] = gl::Buffer::fromVector(class_indices);
            CasterBuffer c;
            c.positions = {vertices_.id(), 0, vertices_.size()};
            c.stride = 6 * sizeof(float);
            c.indices = {class_indices_[k].id(), 0, class_indices_[k].size()};
            c.triangles = static_cast<uint32_t>(class_indices.size() / 3);
            c.caster_class = k == 0 ? CasterClass::Closed : CasterClass::Open;
            caster_buffers_.push_back(c);
        }
        // Triangles with adjacency (by position), for the soft pipeline's silhouette skip.
        const std::vector<uint32_t> adjacency =
            penumbra::triangleAdjacency(positions_.data(), positions_.size(), indices.data(), indices.size());
        adjacency_ = gl::Buffer::fromVector(adjacency);
        glCreateVertexArrays(1, &vao_);
        glCreateVertexArrays(1, &adjacency_vao_);
        if (vertices_.id()) glVertexArrayVertexBuffer(adjacency_vao_, 0, vertices_.id(), 0, 6 * sizeof(float));
        if (adjacency_.id()) glVertexArrayElementBuffer(adjacency_vao_, adjacency_.id());
        glEnableVertexArrayAttrib(adjacency_vao_, 0);
        glVertexArrayAttribFormat(adjacency_vao_, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(adjacency_vao_, 0, 0);
        if (vertices_.id()) {
            glVertexArrayVertexBuffer(vao_, 0, vertices_.id(), 0, 6 * sizeof(float));
        }
        if (indices_.id()) glVertexArrayElementBuffer(vao_, indices_.id());
        for (GLuint a = 0; a < 2; ++a) {
            glEnableVertexArrayAttrib(vao_, a);
            glVertexArrayAttribFormat(vao_, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
            glVertexArrayAttribBinding(vao_, a, 0);
        }
        gl::checkErrors("penumbra::scene::GpuScene upload");
    }
    GpuScene(GpuScene&& other) noexcept
        : vertices_(std::move(other.vertices_)),
          indices_(std::move(other.indices_)),
          face_normals_(std::move(other.face_normals_)),
          adjacency_(std::move(other.adjacency_)),
          class_indices_{std::move(other.class_indices_[0]), std::move(other.class_indices_[1])},
          caster_buffers_(std::move(other.caster_buffers_)),
          vao_(std::exchange(other.vao_, 0)),
          adjacency_vao_(std::exchange(other.adjacency_vao_, 0)),
          index_count_(other.index_count_),
          ranges_(std::move(other.ranges_)),
          positions_(std::move(other.positions_)),
          cpu_indices_(std::move(other.cpu_indices_)) {}
    GpuScene& operator=(GpuScene&&) = delete;
    GpuScene(const GpuScene&) = delete;
    GpuScene& operator=(const GpuScene&) = delete;
    ~GpuScene() {
        if (vao_) glDeleteVertexArrays(1, &vao_);
        if (adjacency_vao_) glDeleteVertexArrays(1, &adjacency_vao_);
    }

    GLuint vertexArray() const { return vao_; }
    GLuint vertexBuffer() const { return vertices_.id(); }  ///< interleaved position, normal (6 floats)
    GLuint indexBuffer() const { return indices_.id(); }    ///< uint triangle list, global vertex ids
    GLuint faceNormalBuffer() const { return face_normals_.id(); }  ///< vec4 per triangle (xyz unit, w = 1 closed mesh)
    uint32_t indexCount() const { return index_count_; }
    uint32_t triangleCount() const { return index_count_ / 3; }
    const std::vector<Range>& ranges() const { return ranges_; }
    /// The casters as buffers (SoftLightPass::Compute): the closed meshes' triangles, then the
    /// others', each class in one index buffer (absent when it has none).
    const std::vector<CasterBuffer>& casterBuffers() const { return caster_buffers_; }
    /// All vertex positions / indices as uploaded (global ids), for CPU twins and the oracle.
    const std::vector<glm::vec3>& positions() const { return positions_; }
    const std::vector<uint32_t>& indices() const { return cpu_indices_; }

    /// Draws every mesh (or one range) as GL_TRIANGLES with the bound program.
    void draw() const {
        glBindVertexArray(vao_);
        if (index_count_) glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(index_count_), GL_UNSIGNED_INT, nullptr);
    }
    /// Draws every mesh as GL_TRIANGLES_ADJACENCY (penumbra::triangleAdjacency over all meshes,
    /// positions at attribute 0): a soft pipeline's DrawAdjacency callback.
    void drawAdjacency() const {
        glBindVertexArray(adjacency_vao_);
        if (index_count_)
            glDrawElements(GL_TRIANGLES_ADJACENCY, static_cast<GLsizei>(2 * index_count_), GL_UNSIGNED_INT, nullptr);
    }
    /// Draws the closed meshes (closed = true) or the others: a pipeline's caster callback
    /// (CasterClass::Closed / Open).
    void drawClass(bool closed) const {
        for (const Range& r : ranges_)
            if (r.closed == closed) draw(r);
    }
    void draw(const Range& range) const {
        glBindVertexArray(vao_);
        if (range.index_count) {
            glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(range.index_count), GL_UNSIGNED_INT,
                           reinterpret_cast<const void*>(uintptr_t(range.first_index) * sizeof(uint32_t)));
        }
    }

private:
    gl::Buffer vertices_, indices_, face_normals_, adjacency_;
    gl::Buffer class_indices_[2];  // closed, open
    std::vector<CasterBuffer> caster_buffers_;
    GLuint vao_ = 0, adjacency_vao_ = 0;
    uint32_t index_count_ = 0;
    std::vector<Range> ranges_;
    std::vector<glm::vec3> positions_;
    std::vector<uint32_t> cpu_indices_;
};

/// A camera G-buffer and its view samples as SSBOs (one entry per pixel, row-major, bottom row first).
class GBuffer {
public:
    GBuffer(uint32_t width, uint32_t height) : width_(width), height_(height) {
        PENUMBRA_CHECK(width > 0 && height > 0 && width <= 16384 && height <= 16384, "penumbra::scene::GBuffer: size ",
                       width, "x", height, " is outside [1, 16384]");
        const GLenum formats[3] = {GL_RGBA32F, GL_RGBA32F, GL_RGBA16F};
        for (int i = 0; i < 3; ++i) {
            color_[i] = gl::Texture(GL_TEXTURE_2D);
            glTextureStorage2D(color_[i].id(), 1, formats[i], static_cast<GLsizei>(width), static_cast<GLsizei>(height));
        }
        depth_ = gl::Texture(GL_TEXTURE_2D);
        glTextureStorage2D(depth_.id(), 1, GL_DEPTH_COMPONENT32F, static_cast<GLsizei>(width), static_cast<GLsizei>(height));
        glCreateFramebuffers(1, &fbo_);
        for (int i = 0; i < 3; ++i) glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT0 + i, color_[i].id(), 0);
        glNamedFramebufferTexture(fbo_, GL_DEPTH_ATTACHMENT, depth_.id(), 0);
        const GLenum draw_buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
        glNamedFramebufferDrawBuffers(fbo_, 3, draw_buffers);
        PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                       "penumbra::scene::GBuffer: framebuffer incomplete");
        program_ = gl::buildProgram({"penumbra/scene/gbuffer.vert.glsl", "penumbra/scene/gbuffer.frag.glsl"});
        const size_t pixels = size_t(width) * height;
        positions_ = gl::Buffer(pixels * 16);
        faces_ = gl::Buffer(pixels * 16);
        gl::checkErrors("penumbra::scene::GBuffer creation");
    }
    GBuffer(GBuffer&&) = delete;
    GBuffer(const GBuffer&) = delete;
    GBuffer& operator=(const GBuffer&) = delete;
    ~GBuffer() {
        if (fbo_) glDeleteFramebuffers(1, &fbo_);
    }

    /// Renders the scene from `view_projection` and refreshes the view-sample SSBOs.
    void render(const GpuScene& scene, const glm::mat4& view_projection) {
        GLint old_viewport[4];
        glGetIntegerv(GL_VIEWPORT, old_viewport);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        glViewport(0, 0, static_cast<GLsizei>(width_), static_cast<GLsizei>(height_));
        const float zero[4] = {0, 0, 0, 0};
        for (int i = 0; i < 3; ++i) glClearNamedFramebufferfv(fbo_, GL_COLOR, i, zero);
        const float one = 1.0f;
        glClearNamedFramebufferfv(fbo_, GL_DEPTH, 0, &one);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDisable(GL_CULL_FACE);
        program_.use();
        glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(view_projection));
        glUniform1ui(1, 0u);
        const glm::dmat4 inverse = glm::inverse(glm::dmat4(view_projection));
        glUniformMatrix4dv(2, 1, GL_FALSE, glm::value_ptr(inverse));
        glUniform2f(3, float(width_), float(height_));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, scene.faceNormalBuffer());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, scene.vertexBuffer());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, scene.indexBuffer());
        scene.draw();
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glViewport(old_viewport[0], old_viewport[1], old_viewport[2], old_viewport[3]);
        // Texture -> SSBO on the GPU (pixel-pack buffer), so view samples never leave the device.
        copyToBuffer(color_[0].id(), positions_);
        copyToBuffer(color_[1].id(), faces_);
        gl::checkErrors("penumbra::scene::GBuffer::render");
    }

    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }
    GLuint positionTexture() const { return color_[0].id(); }
    GLuint faceTexture() const { return color_[1].id(); }
    GLuint shadingNormalTexture() const { return color_[2].id(); }
    GLuint depthTexture() const { return depth_.id(); }
    /// vec4 per pixel: world position, w = 1 where a surface was hit, 0 for background.
    const gl::Buffer& positionBuffer() const { return positions_; }
    /// vec4 per pixel: unit face normal (outward for closed meshes, towards the camera for open
    /// ones), w = triangle id (float bits).
    const gl::Buffer& faceBuffer() const { return faces_; }

private:
    uint32_t width_, height_;
    gl::Texture color_[3];
    gl::Texture depth_;
    GLuint fbo_ = 0;
    gl::Program program_;
    gl::Buffer positions_, faces_;

    void copyToBuffer(GLuint texture, const gl::Buffer& buffer) const {
        glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, buffer.id());
        glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(buffer.size()), nullptr);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        glMemoryBarrier(GL_PIXEL_BUFFER_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    }
};

}  // namespace penumbra::scene

#endif
