// penumbra — the quadtree light-volume tessellator (billeter2010) on the GPU. The rules, the pure
// setup and the CPU twin are penumbra/light_volume.hpp; this header runs them with compute shaders
// and the scan block (no geometry shader, no transform feedback: see below).
//
// Integration summary
//   needs:    GL 4.5 with fp64 in shaders; PENUMBRA_GL_HEADER; the light's shadow map as a depth
//             (or R32F) texture of R x R texels, R = setup.resolution (read with texelFetch through
//             the tessellator's own sampler, so the texture's compare mode does not matter).
//   produces: triangles() (uint[3 * setup.maxTriangles()]: 3 packed vertices per triangle, x | y << 16
//             on the (R + 1)^2 lattice or PENUMBRA_LV_APEX, outward, the floor first, in the CPU
//             twin's order), corners() (float[(R + 1)^2]: the lattice depths), indirect()
//             (DrawArraysIndirectCommand {3 T, 1, 0, 0}, then the floor's triangle count and T): a
//             vertex shader that fetches triangles()[gl_VertexID] and unprojects it draws the volume
//             with one glDrawArraysIndirect.
//   per frame: tessellate() — (1) lattice depths, (2) per level k = 1 .. L, finest first: restriction
//             of level k - 1, then level k's flags — closure (a subdivided child) or else the flatness
//             test, one invocation per row of a cell, a cell with a subdivided child not tested
//             (closure decides it), (3) triangles per item (cells of every level, then 4 R border
//             segments), (4) exclusive scan, (5) emission at the scanned offsets, (6) the draw
//             command. Nothing is allocated, queried, read back or thrown per frame.
//   equals:   tessellateLightVolume (and lightVolumeCornerDepths) bit for bit where float and double
//             + - * / are correctly rounded and not fused (llvmpipe; `precise` forbids the fusing):
//             the same lattice depths, flags, triangles and order.
//   state:    tessellate() binds its programs, the params uniform range (binding 1), storage
//             bindings 0-4 and what the scanner binds, the depth texture and the tessellator's
//             sampler on texture unit 0; restores none of them. Ends with
//             GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT.
//
// What compute + scan changes against the seed's geometry shader + transform feedback: the seed
// walks the quadtree top-down, one geometry-shader pass per level, each level's output fed back as
// the next one's input, so its output order depends on the driver's primitive order and its size is
// known only on the CPU after a query. Here every level's flags are computed data-parallel, the
// emission is one pass whose output offsets come from a scan, so the mesh is deterministic (the CPU
// twin's order), its size stays on the GPU (the indirect command), and no pass waits on the CPU.
#ifndef PENUMBRA_GL_LIGHT_VOLUME_HPP
#define PENUMBRA_GL_LIGHT_VOLUME_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/detail/dispatch.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/scan.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/airlight.hpp"
#include "penumbra/light_volume.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <cstddef>
#include <cstdint>
#include <ios>
#include <vector>

namespace penumbra::gl {

/// GPU time of the tessellator's stages (enableStageTimers(); stageTimes() reads them back: for
/// tools and benchmarks, not for the frame), milliseconds. edge_map: lattice depths + the flags of
/// every level with closure and restriction (the seed's Laplacian, edge map and its mip hierarchy);
/// tessellate: counts, scan, emission, command.
struct LightVolumeStageTimes {
    double edge_map = 0, tessellate = 0;
    double total() const { return edge_map + tessellate; }
};

class LightVolumeTessellator {
public:
    /// Load time: buffers for setup.maxTriangles() triangles and the programs. Throws penumbra::Error
    /// when the triangle buffer would exceed the driver's shader-storage block size.
    explicit LightVolumeTessellator(const LightVolumeSetup& setup, const ShaderLibrary& library = ShaderLibrary::embedded())
        : setup_(setup), scanner_(ScanOptions{}, library) {
        const uint32_t r = setup.resolution;
        PENUMBRA_CHECK(r >= 2 && (r & (r - 1)) == 0 && (1u << setup.levels) == r,
                       "LightVolumeTessellator: the setup is not from lightVolumeSetup (R = ", r, ")");
        cells_ = lightVolumeCells(setup);
        items_ = cells_ + 4ull * r;
        GLint64 max_block = 0;
        glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
        const uint64_t triangle_bytes = 12ull * setup.maxTriangles();
        PENUMBRA_CHECK(triangle_bytes <= static_cast<uint64_t>(max_block) && 4ull * (items_ + 1) <= static_cast<uint64_t>(max_block),
                       "LightVolumeTessellator: a ", r, "^2 shadow map needs a triangle buffer of ", triangle_bytes,
                       " bytes, over the driver's shader-storage block size of ", max_block, " bytes");
        corners_ = Buffer(4ull * (r + 1) * (r + 1));
        flags_ = Buffer(4ull * cells_);
        counts_ = Buffer(4ull * (items_ + 1));
        triangles_ = Buffer(triangle_bytes);
        indirect_ = Buffer(32);
        GLint alignment = 256;
        glGetIntegerv(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT, &alignment);
        ubo_stride_ = static_cast<uint32_t>((sizeof(LightVolumeParams) + alignment - 1) / alignment * alignment);
        std::vector<uint8_t> staging(static_cast<size_t>(ubo_stride_) * (setup.levels + 1), 0);
        for (uint32_t k = 0; k <= setup.levels; ++k) {
            const LightVolumeParams p = lightVolumeParams(setup, k);
            std::memcpy(staging.data() + static_cast<size_t>(k) * ubo_stride_, &p, sizeof(p));
        }
        params_ = Buffer(staging.size(), staging.data());
        scanner_.reserve(items_ + 1);

        corners_program_ = buildComputeProgram("penumbra/light_volume/corners.comp.glsl", {}, library);
        flags_program_ = buildComputeProgram("penumbra/light_volume/deviation.comp.glsl", {}, library);
        restrict_program_ = buildComputeProgram("penumbra/light_volume/restrict.comp.glsl", {}, library);
        for (int pass = 0; pass < 2; ++pass)
            emit_program_[pass] = buildComputeProgram("penumbra/light_volume/emit.comp.glsl", {{"PENUMBRA_LV_PASS", std::to_string(pass)}}, library);
        indirect_program_ = buildComputeProgram("penumbra/light_volume/indirect.comp.glsl", {}, library);
        glCreateSamplers(1, &sampler_);
        glSamplerParameteri(sampler_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glSamplerParameteri(sampler_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glSamplerParameteri(sampler_, GL_TEXTURE_COMPARE_MODE, GL_NONE);
        glSamplerParameteri(sampler_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glSamplerParameteri(sampler_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    LightVolumeTessellator(const LightVolumeTessellator&) = delete;
    LightVolumeTessellator& operator=(const LightVolumeTessellator&) = delete;
    ~LightVolumeTessellator() {
        if (sampler_) glDeleteSamplers(1, &sampler_);
    }

    /// Load time: bracket the two stages with GL_TIME_ELAPSED queries, or (wall_clock: drivers whose
    /// queries do not measure durations, e.g. llvmpipe) with glFinish + the wall clock, which
    /// synchronises the frame: a tool's setting, never an engine's.
    void enableStageTimers(bool wall_clock = false) { timers_.enable(wall_clock); }
    /// Read-back of the last tessellation's stage times (waits for the GPU).
    LightVolumeStageTimes stageTimes() const {
        LightVolumeStageTimes t;
        t.edge_map = timers_.milliseconds(0);
        t.tessellate = timers_.milliseconds(1);
        return t;
    }

    const LightVolumeSetup& setup() const { return setup_; }
    BufferRange triangles() const { return {triangles_.id(), 0, triangles_.size()}; }
    BufferRange corners() const { return {corners_.id(), 0, corners_.size()}; }
    BufferRange indirect() const { return {indirect_.id(), 0, indirect_.size()}; }
    BufferRange flags() const { return {flags_.id(), 0, flags_.size()}; }

    /// Tessellates the light volume of `depth_texture` (R x R, see the summary). Per-frame contract:
    /// no allocation, no query, no read-back, no throw.
    void tessellate(GLuint depth_texture) {
        const uint32_t r = setup_.resolution, levels = setup_.levels;
        const uint32_t zero = 0;
        timers_.begin(0);
        // The last tessellation's shaders wrote the flags: a clear is ordered after those writes
        // only by this bit (GL 4.5 §7.13.2).
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glClearNamedBufferData(flags_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glBindTextureUnit(PENUMBRA_LV_DEPTH_UNIT, depth_texture);
        glBindSampler(PENUMBRA_LV_DEPTH_UNIT, sampler_);
        bindAll(0);
        const uint64_t lattice = uint64_t(r + 1) * (r + 1);
        dispatch(corners_program_, lattice);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        for (uint32_t k = 1; k <= levels; ++k) {
            if (k >= 2) {
                bindLevel(k - 1);
                dispatch(restrict_program_, uint64_t(r >> (k - 1)) * (r >> (k - 1)));
                glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            }
            bindLevel(k);
            dispatch(flags_program_, uint64_t(r >> k) * (r >> k) * ((1ull << k) + 1));  // a row of every cell
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        timers_.end();
        timers_.begin(1);
        bindLevel(0);
        dispatch(emit_program_[0], items_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        const BufferRange counts{counts_.id(), 0, counts_.size()};
        scanner_.scan(ScanKind::Exclusive, counts, counts, items_ + 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT);
        bindAll(0);  // the scan used bindings of its own
        dispatch(emit_program_[1], items_);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glUseProgram(indirect_program_.id());
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
        timers_.end();
    }

    /// Read-backs (tests and tools only): the mesh as the CPU twin returns it, the lattice depths.
    LightVolumeMesh readMesh() const {
        uint32_t command[8];
        glGetNamedBufferSubData(indirect_.id(), 0, sizeof(command), command);
        LightVolumeMesh mesh;
        mesh.resolution = setup_.resolution;
        mesh.floor_triangles = command[4];
        mesh.triangles.resize(3ull * command[5]);
        if (!mesh.triangles.empty())
            glGetNamedBufferSubData(triangles_.id(), 0, static_cast<GLsizeiptr>(4 * mesh.triangles.size()), mesh.triangles.data());
        return mesh;
    }
    std::vector<float> readCorners() const {
        std::vector<float> corners(static_cast<size_t>(setup_.resolution + 1) * (setup_.resolution + 1));
        glGetNamedBufferSubData(corners_.id(), 0, static_cast<GLsizeiptr>(4 * corners.size()), corners.data());
        return corners;
    }

private:
    void bindLevel(uint32_t k) {
        gl::bindRange(GL_UNIFORM_BUFFER, PENUMBRA_LV_BINDING_PARAMS, params_.id(), static_cast<GLintptr>(k) * ubo_stride_,
                      sizeof(LightVolumeParams));
    }
    void bindAll(uint32_t k) {
        bindLevel(k);
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_CORNERS, corners_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_FLAGS, flags_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_COUNTS, counts_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_TRIANGLES, triangles_.id());
        gl::bindBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_INDIRECT, indirect_.id());
    }
    void dispatch(const Program& program, uint64_t invocations) {
        if (invocations == 0) return;
        const auto grid = ::penumbra::detail::foldDispatch(::penumbra::detail::divUp(invocations, PENUMBRA_LV_GROUP_SIZE));
        glUseProgram(program.id());
        glDispatchCompute(grid.x, grid.y, 1);
    }
    LightVolumeSetup setup_;
    Scanner scanner_;
    uint64_t cells_ = 0, items_ = 0;
    uint32_t ubo_stride_ = 256;
    Buffer corners_, flags_, counts_, triangles_, indirect_, params_;
    Program corners_program_, flags_program_, restrict_program_, emit_program_[2], indirect_program_;
    GLuint sampler_ = 0;
    StageTimers<2> timers_;
};

/// What one frame of the render needs besides the volume: the camera and the light, in double (the
/// host forms every matrix relative to the eye, so the shaders' floats stay small), and the colour
/// the airlight scales.
struct LightVolumeView {
    glm::dmat4 camera_view_projection{1.0};  ///< world -> the camera's clip space
    glm::dvec3 eye{0.0};                     ///< the camera's position
    glm::dmat4 light_view_projection{1.0};   ///< the shadow map's (the tessellated one)
    glm::dvec3 light_position{0.0};          ///< the spot light (the volume's apex)
    glm::vec3 colour{1.0f};                  ///< lit += colour * airlight
};

/// billeter2010's render of a tessellated light volume: every volume triangle drawn without depth
/// test or culling into an RG32F accumulation target the renderer owns (viewport W x H), each
/// fragment a crossing of its pixel's ray (volume.frag.glsl: entering -A(t), leaving +A(t), t
/// clamped to the scene's depth by counting crossings behind it), then a composite that adds
/// colour * airlight to the engine's lit image. The twin is reference::LightVolumeRaycaster.
///   needs:   the tessellator's buffers (same frame), the camera's depth texture (W x H, window
///            depth, 1 = background; any compare mode: read through the renderer's sampler), the
///            engine's lit image (W x H, GL_RGBA32F or GL_RGBA16F, bound as an image).
///   state:   render() binds its framebuffer, viewport, programs, an empty vertex array, the draw-
///            indirect buffer, uniform binding 2, storage bindings 0 and 3, texture units 1-3 (with
///            samplers) and image unit 0; enables blending (ONE, ONE) and the colour writes of draw
///            buffer 0, depth clamp, sets gl::setPassRasterState's rasterizer state (before the
///            clear, which obeys the scissor test: scissor off, polygon fill, clip distances off,
///            clip control lower-left / -1..1 so gl_FrontFacing keeps its sign, front faces
///            counter-clockwise, ...), disables depth test and culling; restores none of them. Ends with
///            GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT.
class LightVolumeRenderer {
public:
    /// Load time: the accumulation target, the airlight table texture and the programs. Throws
    /// penumbra::Error for an empty viewport, a lit format other than GL_RGBA32F / GL_RGBA16F, or an
    /// airlight setup without its table (AirlightMethod::Quadrature renders nothing here).
    LightVolumeRenderer(uint32_t width, uint32_t height, const AirlightSetup& airlight, GLenum lit_format = GL_RGBA32F,
                        const ShaderLibrary& library = ShaderLibrary::embedded())
        : width_(width), height_(height) {
        PENUMBRA_CHECK(width >= 1 && height >= 1 && width <= 16384 && height <= 16384, "LightVolumeRenderer: viewport ", width, "x",
                       height, " is outside [1, 16384]");
        PENUMBRA_CHECK(lit_format == GL_RGBA32F || lit_format == GL_RGBA16F,
                       "LightVolumeRenderer: the lit image must be GL_RGBA32F or GL_RGBA16F (got 0x", std::hex, lit_format, ")");
        PENUMBRA_CHECK(airlight.method == AirlightMethod::Table && !airlight.table.empty(),
                       "LightVolumeRenderer: the airlight setup must use the table (isotropic medium); got method ",
                       uint32_t(airlight.method));
        medium_ = airlight.shaderMedium();
        airlight_params_ = airlight.shaderParams();
        table_ = Texture(GL_TEXTURE_2D);
        glTextureStorage2D(table_.id(), 1, GL_R32F, GLsizei(airlight.tableWidth()), GLsizei(airlight.tableHeight()));
        glTextureSubImage2D(table_.id(), 0, 0, 0, GLsizei(airlight.tableWidth()), GLsizei(airlight.tableHeight()), GL_RED, GL_FLOAT,
                            airlight.table.data());
        accumulation_ = Texture(GL_TEXTURE_2D);
        glTextureStorage2D(accumulation_.id(), 1, GL_RG32F, GLsizei(width), GLsizei(height));
        glCreateFramebuffers(1, &fbo_);
        glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT0, accumulation_.id(), 0);
        PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                       "LightVolumeRenderer: the RG32F accumulation target is not renderable");
        glCreateVertexArrays(1, &vao_);
        glCreateSamplers(2, samplers_);
        glSamplerParameteri(samplers_[0], GL_TEXTURE_MIN_FILTER, GL_LINEAR);  // the airlight table
        glSamplerParameteri(samplers_[0], GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glSamplerParameteri(samplers_[1], GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // depth, accumulation
        glSamplerParameteri(samplers_[1], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glSamplerParameteri(samplers_[1], GL_TEXTURE_COMPARE_MODE, GL_NONE);
        for (GLuint sampler : samplers_) {
            glSamplerParameteri(sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glSamplerParameteri(sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        }
        params_ = Buffer(sizeof(shared::PenumbraLightVolumeRenderParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
        volume_program_ = buildProgram({"penumbra/light_volume/volume.vert.glsl", "penumbra/light_volume/volume.frag.glsl"}, {}, library);
        composite_program_ = buildComputeProgram("penumbra/light_volume/composite.comp.glsl",
                                                 {{"PENUMBRA_LV_LIT_FORMAT", lit_format == GL_RGBA32F ? "rgba32f" : "rgba16f"}}, library);
        march_program_ = buildComputeProgram("penumbra/light_volume/ray_march.comp.glsl", {{"PENUMBRA_LV_LIT_FORMAT", "rgba32f"}}, library);
        lit_format_ = lit_format;
    }
    LightVolumeRenderer(const LightVolumeRenderer&) = delete;
    LightVolumeRenderer& operator=(const LightVolumeRenderer&) = delete;
    ~LightVolumeRenderer() {
        if (fbo_) glDeleteFramebuffers(1, &fbo_);
        if (vao_) glDeleteVertexArrays(1, &vao_);
        if (samplers_[0]) glDeleteSamplers(2, samplers_);
    }

    /// A new medium or intensity (the table does not depend on them); per frame if need be.
    void setMedium(const AirlightSetup& airlight) { medium_ = airlight.shaderMedium(); }
    /// The accumulation target of the last render (RG32F: red = sum of clamped crossings, green =
    /// signed count behind the scene).
    GLuint accumulation() const { return accumulation_.id(); }

    /// Draws the volume `tessellator` produced this frame and adds its airlight to `lit_texture`.
    /// Per-frame contract: no allocation, no query, no read-back, no throw.
    void render(const LightVolumeTessellator& tessellator, const LightVolumeView& view, GLuint scene_depth_texture,
                GLuint lit_texture) {
        upload(view, tessellator.setup().resolution, 0);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo_);
        glViewport(0, 0, GLsizei(width_), GLsizei(height_));
        setPassRasterState();  // before the clear too: it obeys the scissor test and the colour mask
        glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        glClearNamedFramebufferfv(fbo_, GL_COLOR, 0, zero);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_RASTERIZER_DISCARD);
        glEnable(GL_DEPTH_CLAMP);
        glEnablei(GL_BLEND, 0);
        glBlendEquationi(0, GL_FUNC_ADD);
        glBlendFunci(0, GL_ONE, GL_ONE);
        gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_LV_BINDING_RENDER_PARAMS, params_.id());
        const BufferRange corners = tessellator.corners(), triangles = tessellator.triangles(), indirect = tessellator.indirect();
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_CORNERS, corners.buffer, GLintptr(corners.offset),
                      GLsizeiptr(corners.size));
        gl::bindRange(GL_SHADER_STORAGE_BUFFER, PENUMBRA_LV_BINDING_TRIANGLES, triangles.buffer, GLintptr(triangles.offset),
                      GLsizeiptr(triangles.size));
        glBindTextureUnit(PENUMBRA_LV_AIRLIGHT_UNIT, table_.id());
        glBindSampler(PENUMBRA_LV_AIRLIGHT_UNIT, samplers_[0]);
        glBindTextureUnit(PENUMBRA_LV_SCENE_DEPTH_UNIT, scene_depth_texture);
        glBindSampler(PENUMBRA_LV_SCENE_DEPTH_UNIT, samplers_[1]);
        glBindVertexArray(vao_);
        glUseProgram(volume_program_.id());
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect.buffer);
        glDrawArraysIndirect(GL_TRIANGLES, reinterpret_cast<const void*>(static_cast<uintptr_t>(indirect.offset)));

        glBindTextureUnit(PENUMBRA_LV_ACCUMULATION_UNIT, accumulation_.id());
        glBindSampler(PENUMBRA_LV_ACCUMULATION_UNIT, samplers_[1]);
        glBindImageTexture(PENUMBRA_LV_LIT_IMAGE, lit_texture, 0, GL_FALSE, 0, GL_READ_WRITE, lit_format_);
        glUseProgram(composite_program_.id());
        glDispatchCompute((width_ + 7) / 8, (height_ + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    }

    /// The baseline an engine would run instead: ray march the shadow map (R x R, window depth) in
    /// `steps` steps per pixel over its ray's stretch inside the spot's frustum and in front of the
    /// scene, each lit step's airlight exact (ray_march.comp.glsl; twin: reference::rayMarchExact
    /// with ShadowMapLookup::Nearest), and add colour * airlight to `lit_texture` (GL_RGBA32F).
    /// Binds texture units 1, 2, 4 and image unit 0. Per frame: no allocation, query or read-back.
    void rayMarch(GLuint shadow_map, uint32_t resolution, uint32_t steps, const LightVolumeView& view, GLuint scene_depth_texture,
                  GLuint lit_texture) {
        upload(view, resolution, steps);
        gl::bindBase(GL_UNIFORM_BUFFER, PENUMBRA_LV_BINDING_RENDER_PARAMS, params_.id());
        glBindTextureUnit(PENUMBRA_LV_AIRLIGHT_UNIT, table_.id());
        glBindSampler(PENUMBRA_LV_AIRLIGHT_UNIT, samplers_[0]);
        glBindTextureUnit(PENUMBRA_LV_SCENE_DEPTH_UNIT, scene_depth_texture);
        glBindSampler(PENUMBRA_LV_SCENE_DEPTH_UNIT, samplers_[1]);
        glBindTextureUnit(PENUMBRA_LV_SHADOW_MAP_UNIT, shadow_map);
        glBindSampler(PENUMBRA_LV_SHADOW_MAP_UNIT, samplers_[1]);
        glBindImageTexture(PENUMBRA_LV_LIT_IMAGE, lit_texture, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        glUseProgram(march_program_.id());
        glDispatchCompute((width_ + 7) / 8, (height_ + 7) / 8, 1);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    }

private:
    /// The constants block of one frame (matrices relative to the eye, formed in double).
    void upload(const LightVolumeView& view, uint32_t resolution, uint32_t steps) {
        shared::PenumbraLightVolumeRenderParams p{};
        const glm::dmat4 to_eye = glm::translate(glm::dmat4(1.0), -view.eye);
        const glm::dmat4 from_eye = glm::translate(glm::dmat4(1.0), view.eye);
        p.light_to_eye = glm::mat4(to_eye * glm::inverse(view.light_view_projection));
        const glm::dmat4 camera = view.camera_view_projection * from_eye;
        p.camera_view_projection = glm::mat4(camera);
        p.camera_inverse = glm::mat4(glm::inverse(camera));
        p.eye_to_light = glm::mat4(view.light_view_projection * from_eye);
        p.light = glm::vec4(glm::vec3(view.light_position - view.eye), 0.0f);
        p.medium = medium_;
        p.airlight = airlight_params_;
        p.colour = glm::vec4(view.colour, 0.0f);
        p.size = glm::uvec4(resolution, width_, height_, 0u);
        p.march = glm::uvec4(steps, 0u, 0u, 0u);
        glNamedBufferSubData(params_.id(), 0, sizeof(p), &p);
    }

    uint32_t width_ = 0, height_ = 0;
    GLenum lit_format_ = GL_RGBA32F;
    glm::vec4 medium_{0.0f}, airlight_params_{0.0f};
    Texture table_, accumulation_;
    GLuint fbo_ = 0, vao_ = 0;
    GLuint samplers_[2] = {0, 0};
    Buffer params_;
    Program volume_program_, composite_program_, march_program_;
};

}  // namespace penumbra::gl

#endif
