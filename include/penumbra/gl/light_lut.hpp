// penumbra — the GL executor of the light-sample LUT generator (sintorn2008 §4.2, Fig. 6):
// penumbra::LightLutGenerator (GL 4.5 compute with fp64), byte-identical to generateLightLut.
// Pure setup, the CPU generator and the lookups' CPU twins are in penumbra/light_lut.hpp (no GL);
// the GLSL lookups are shaders/penumbra/light_lut/lookup.glsl.
//
// Integration summary
//   needs:    PENUMBRA_GL_HEADER (see gl.hpp), a current GL 4.5 context with fp64 (core since 4.0);
//             shaders from the embedded table or a ShaderLibrary you pass.
//   setup:    LightLutGenerator(library, bindings, options) queries the limits and compiles
//             generate.comp.glsl; reserve(setup) uploads the generator's inputs (samples, normal and
//             distance cells: setup.inputBytes(), plus the 48-byte parameter block) into buffers it
//             owns and plans the dispatches; validate(setup, table) checks your output range against
//             GL once (queries, throws penumbra::Error naming the value).
//   per call: generate(setup, table) writes setup.texelCount() uvec4s into `table` in exactly the
//             CPU layout (centre masks, then in certified mode the uncertain masks at
//             params.uncertain_offset): three glBindBuffersRange (parameter block, normal and
//             distance cells), one glUseProgram, one glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT),
//             then per planned dispatch two or three glBindBuffersRange (the samples' and the
//             output windows) + glProgramUniform4ui + glDispatchCompute. No heap allocation, no glGet* / glIs* /
//             glGetError, no read-back, no exception. Misuse it can see without GL returns a Status
//             after PENUMBRA_ASSERT and issues no GL call:
//               NotReserved    no reserve(), or a setup whose parameter block or array sizes differ
//                              from the reserved one (the arrays' contents are not compared: the
//                              generator uses those reserve() uploaded);
//               RangeTooSmall  `table` null or shorter than setup.tableBytes();
//               Misaligned     `table.offset` not a multiple of GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT.
//   read-back (explicit, waits for the GPU; tests and tools): readLightLut(setup, table).
//   textures (setup helpers, optional): createLightLutTexture(setup) (RGBA32UI 3D, R_n x R_n x R_d)
//             and uploadLightLutTexture(texture, setup, table, index, uncertain) copy one table from
//             the buffer on the GPU (pixel-unpack buffer), for lookups through texelFetch.
//
// Chunking. A dispatch covers whole tables, or for a table larger than the largest binding
// (GL_MAX_SHADER_STORAGE_BLOCK_SIZE, e.g. 256^3 x 16 bytes = 256 MiB) a slab of its distance cells;
// every binding is a window of at most that size, and every grid is folded into x, y within
// GL_MAX_COMPUTE_WORK_GROUP_COUNT. reserve() decides it (LightLutGenerator::dispatches()).
//
// GL state contract of generate() (Status::Ok): changes and does not restore the current program
// (left at the generator's), the indexed GL_SHADER_STORAGE_BUFFER bindings LightLutBindings::samples,
// normal_cells, distance_cells, table and (certified setups) uncertain, and the indexed
// GL_UNIFORM_BUFFER binding LightLutBindings::params. Nothing else (no unbinding, no error
// draining). No barrier follows the last dispatch: before reading the LUT issue the barrier for
// how you read it (GL_SHADER_STORAGE_BARRIER_BIT for SSBO reads, GL_PIXEL_BUFFER_BARRIER_BIT |
// GL_TEXTURE_UPDATE_BARRIER_BIT before a texture upload from it, GL_BUFFER_UPDATE_BARRIER_BIT for
// glGetBufferSubData; readLightLut and uploadLightLutTexture issue theirs).
//
// Errors at setup (penumbra::Error naming the value): bindings out of the driver's range or SSBO
// bindings that coincide, shader errors, a failed allocation (GL_BUFFER_SIZE query, the GL error
// queue is not touched), a setup whose arrays do not match its parameters, validate() with a range
// that is not a buffer, lies past GL_BUFFER_SIZE, is misaligned or too small.
#ifndef PENUMBRA_GL_LIGHT_LUT_HPP
#define PENUMBRA_GL_LIGHT_LUT_HPP

#include "penumbra/buffer_range.hpp"
#include "penumbra/detail/dispatch.hpp"
#include "penumbra/gl/gl.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/gl/validate.hpp"
#include "penumbra/light_lut.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <utility>
#include <vector>

namespace penumbra {

/// Binding points of the generator's kernel; value-initialised = the light_lut_shared.h defaults.
/// The five shader-storage indices must differ; params is a uniform-buffer index.
struct LightLutBindings {
    uint32_t samples = PENUMBRA_LUT_BINDING_SAMPLES;
    uint32_t normal_cells = PENUMBRA_LUT_BINDING_NORMAL_CELLS;
    uint32_t distance_cells = PENUMBRA_LUT_BINDING_DISTANCE_CELLS;
    uint32_t table = PENUMBRA_LUT_BINDING_TABLE;          ///< centre masks (output)
    uint32_t uncertain = PENUMBRA_LUT_BINDING_UNCERTAIN;  ///< uncertain masks (output, certified)
    uint32_t params = PENUMBRA_LUT_BINDING_PARAMS;        ///< GL_UNIFORM_BUFFER binding
};

/// Limits the planner uses; 0 = the driver's (value-initialised = all from the driver). Smaller
/// values force chunked dispatches (tests).
struct LightLutGeneratorOptions {
    uint64_t max_binding_bytes = 0;  ///< largest SSBO window (GL_MAX_SHADER_STORAGE_BLOCK_SIZE)
    uint64_t max_groups_x = 0;       ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    uint64_t max_groups_y = 0;       ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[1]
};

/// One planned dispatch of generate(): tables [first_table, first_table + tables), distance cells
/// [first_k, first_k + k_count) of each, and its folded grid.
struct LightLutDispatch {
    uint32_t first_table = 0, tables = 0;
    uint32_t first_k = 0, k_count = 0;
    uint64_t groups = 0;
    uint32_t grid_x = 0, grid_y = 0;
};

namespace detail {

/// An owned immutable-storage buffer, filled at creation; failure detected by a GL_BUFFER_SIZE
/// query (never glGetError).
class LutOwnedBuffer {
public:
    LutOwnedBuffer() = default;
    LutOwnedBuffer(LutOwnedBuffer&& other) noexcept
        : id_(std::exchange(other.id_, 0)), bytes_(std::exchange(other.bytes_, 0)) {}
    LutOwnedBuffer& operator=(LutOwnedBuffer&& other) noexcept {
        if (this != &other) {
            reset();
            id_ = std::exchange(other.id_, 0);
            bytes_ = std::exchange(other.bytes_, 0);
        }
        return *this;
    }
    LutOwnedBuffer(const LutOwnedBuffer&) = delete;
    LutOwnedBuffer& operator=(const LutOwnedBuffer&) = delete;
    ~LutOwnedBuffer() { reset(); }

    GLuint id() const { return id_; }
    uint64_t bytes() const { return bytes_; }
    /// Replaces the contents with `bytes` bytes of `data`; reallocates only when it grows.
    void assign(const void* data, uint64_t bytes, const char* what) {
        bytes = std::max<uint64_t>(bytes, 16);
        if (bytes > bytes_) {
            reset();
            GLuint id = 0;
            glCreateBuffers(1, &id);
            PENUMBRA_CHECK(id != 0, "penumbra::LightLutGenerator::reserve: glCreateBuffers failed for the ", what,
                           " buffer");
            glNamedBufferStorage(id, static_cast<GLsizeiptr>(bytes), nullptr, GL_DYNAMIC_STORAGE_BIT);
            GLint64 size = 0;
            glGetNamedBufferParameteri64v(id, GL_BUFFER_SIZE, &size);
            if (static_cast<uint64_t>(size) != bytes) {
                glDeleteBuffers(1, &id);
                ::penumbra::detail::fail("penumbra::LightLutGenerator::reserve: allocating ", bytes, " bytes of ", what,
                                         " failed (GL_BUFFER_SIZE ", size, " afterwards; GL's own error stays queued)");
            }
            id_ = id;
            bytes_ = bytes;
        }
        if (data) glNamedBufferSubData(id_, 0, static_cast<GLsizeiptr>(bytes), data);
    }
    void reset() {
        if (id_) gl::deleteBuffers(1, &id_);  // bound at indexed points: keeps the generic ones
        id_ = 0;
        bytes_ = 0;
    }

private:
    GLuint id_ = 0;
    uint64_t bytes_ = 0;
};

inline constexpr uint32_t kLutGroupSize = 64;

/// The dispatch list of a LUT (pure arithmetic): whole tables per dispatch while a table fits one
/// binding window, else slabs of distance cells; grids folded within max_x x max_y.
inline std::vector<LightLutDispatch> planLightLut(const shared::PenumbraLutParams& p, uint64_t max_binding_bytes,
                                                  uint64_t max_x, uint64_t max_y) {
    const uint64_t cells = uint64_t(p.resolution_normal) * p.resolution_normal;
    const uint64_t table_bytes = uint64_t(p.texels_per_table) * 16u;
    const uint64_t slab_bytes = cells * 16u;
    const uint64_t max_groups = max_x * max_y;
    PENUMBRA_CHECK(max_binding_bytes >= slab_bytes && max_binding_bytes >= 128u * 32u,
                   "penumbra::LightLutGenerator: the largest shader-storage binding (", max_binding_bytes,
                   " bytes) cannot hold one slice of ", slab_bytes, " bytes");
    std::vector<LightLutDispatch> out;
    auto add = [&](uint32_t first_table, uint32_t tables, uint32_t first_k, uint32_t k_count) {
        LightLutDispatch d;
        d.first_table = first_table;
        d.tables = tables;
        d.first_k = first_k;
        d.k_count = k_count;
        d.groups = uint64_t(tables) * cells * divUp(k_count, kLutGroupSize);
        const DispatchGrid grid = foldDispatch(d.groups, max_x, max_y);
        d.grid_x = grid.x;
        d.grid_y = grid.y;
        out.push_back(d);
    };
    const uint64_t chunks = divUp(p.resolution_distance, kLutGroupSize);
    if (table_bytes <= max_binding_bytes && cells * chunks <= max_groups) {
        // Whole tables: as many as one window (centre, uncertain, samples) and one grid hold.
        uint64_t per = std::min(max_binding_bytes / table_bytes, max_binding_bytes / (128u * 32u));
        per = std::min(per, max_groups / (cells * chunks));
        per = std::max<uint64_t>(per, 1);
        for (uint64_t t = 0; t < p.tables; t += per) {
            add(static_cast<uint32_t>(t), static_cast<uint32_t>(std::min<uint64_t>(per, p.tables - t)), 0,
                p.resolution_distance);
        }
    } else {
        // Slabs of distance cells of one table.
        uint64_t per = max_binding_bytes / slab_bytes;
        const uint64_t grid_k = (max_groups / cells) * kLutGroupSize;
        PENUMBRA_CHECK(grid_k > 0, "penumbra::LightLutGenerator: ", cells, " normal cells exceed the ", max_x, " x ",
                       max_y, " dispatch grid");
        per = std::min(per, grid_k);
        if (per > kLutGroupSize) per -= per % kLutGroupSize;
        for (uint32_t t = 0; t < p.tables; ++t)
            for (uint64_t k = 0; k < p.resolution_distance; k += per) {
                add(t, 1, static_cast<uint32_t>(k), static_cast<uint32_t>(std::min<uint64_t>(per, p.resolution_distance - k)));
            }
    }
    return out;
}

/// The arrays of a setup agree with its parameters (setup-time check).
inline void checkLightLutSetup(const LightLutSetup& s, const char* function) {
    const shared::PenumbraLutParams& p = s.params;
    PENUMBRA_CHECK(p.resolution_normal >= PENUMBRA_LUT_MIN_RESOLUTION && p.resolution_distance >= PENUMBRA_LUT_MIN_RESOLUTION &&
                       p.tables > 0 && p.tables_per_set > 0 &&
                       uint64_t(p.texels_per_table) == uint64_t(p.resolution_normal) * p.resolution_normal * p.resolution_distance,
                   "penumbra::", function, ": the setup's parameter block is not from lightLutSetup");
    PENUMBRA_CHECK(s.samples.size() == size_t(p.tables) * 128u, "penumbra::", function, ": the setup has ",
                   s.samples.size(), " samples, its ", p.tables, " tables need ", size_t(p.tables) * 128u);
    PENUMBRA_CHECK(s.normal_cells.size() == size_t(p.resolution_normal) * p.resolution_normal, "penumbra::", function,
                   ": the setup has ", s.normal_cells.size(), " normal cells, R_n = ", p.resolution_normal);
    PENUMBRA_CHECK(s.distance_cells.size() == p.resolution_distance, "penumbra::", function, ": the setup has ",
                   s.distance_cells.size(), " distance cells, R_d = ", p.resolution_distance);
}

}  // namespace detail

/// Generates light-sample LUTs on the GPU (see the summary at the top of this file). Owns its
/// program and four small input buffers: RAII, movable, not copyable; create, use and destroy it
/// with the same GL context current. A moved-from generator may be destroyed, assigned to or
/// called (generate() then returns Status::NotReserved).
class LightLutGenerator {
public:
    /// Needs a current GL 4.5 context; queries the limits and compiles generate.comp.glsl, pointing
    /// its blocks at `bindings`. Throws penumbra::Error for bad bindings and shader errors.
    explicit LightLutGenerator(const ShaderLibrary& library = ShaderLibrary::embedded(),
                               const LightLutBindings& bindings = {}, const LightLutGeneratorOptions& options = {})
        : bindings_(bindings) {
        checkBindings();
        GLint64 block = 0;
        glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
        max_binding_bytes_ = options.max_binding_bytes ? options.max_binding_bytes : static_cast<uint64_t>(block);
        max_x_ = options.max_groups_x ? options.max_groups_x : static_cast<uint64_t>(gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0));
        max_y_ = options.max_groups_y ? options.max_groups_y : static_cast<uint64_t>(gl::getInteger(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 1));
        ssbo_alignment_ = static_cast<uint32_t>(gl::getInteger(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT));
        PENUMBRA_CHECK(max_binding_bytes_ > 0 && max_x_ > 0 && max_y_ > 0 && ssbo_alignment_ > 0,
                       "penumbra::LightLutGenerator: the driver reported unusable compute limits (is a GL 4.5 context current?)");
        program_ = gl::buildComputeProgram("penumbra/light_lut/generate.comp.glsl", {}, library);
        pointBlocks(program_.id());
    }
    LightLutGenerator(LightLutGenerator&& other) noexcept { *this = std::move(other); }
    LightLutGenerator& operator=(LightLutGenerator&& other) noexcept {
        if (this != &other) {
            bindings_ = other.bindings_;
            max_binding_bytes_ = other.max_binding_bytes_;
            max_x_ = other.max_x_;
            max_y_ = other.max_y_;
            ssbo_alignment_ = other.ssbo_alignment_;
            program_ = std::move(other.program_);
            samples_ = std::move(other.samples_);
            normal_cells_ = std::move(other.normal_cells_);
            distance_cells_ = std::move(other.distance_cells_);
            params_ = std::move(other.params_);
            dispatches_ = std::move(other.dispatches_);
            reserved_params_ = other.reserved_params_;
            reserved_certified_ = other.reserved_certified_;
            reserved_ = std::exchange(other.reserved_, false);
        }
        return *this;
    }
    LightLutGenerator(const LightLutGenerator&) = delete;
    LightLutGenerator& operator=(const LightLutGenerator&) = delete;
    ~LightLutGenerator() = default;

    /// Setup: uploads the setup's samples, normal and distance cells and parameter block (its
    /// inputBytes() + 48 bytes; buffers grow only) and plans the dispatches. A later reserve()
    /// replaces them. Throws penumbra::Error for a setup whose arrays do not match its parameters,
    /// limits that cannot run it, or a failed allocation.
    void reserve(const LightLutSetup& setup) {
        detail::checkLightLutSetup(setup, "LightLutGenerator::reserve");
        dispatches_ = detail::planLightLut(setup.params, max_binding_bytes_, max_x_, max_y_);
        samples_.assign(setup.samples.data(), setup.samples.size() * sizeof(glm::dvec4), "sample");
        normal_cells_.assign(setup.normal_cells.data(), setup.normal_cells.size() * sizeof(glm::dvec4), "normal cell");
        distance_cells_.assign(setup.distance_cells.data(), setup.distance_cells.size() * sizeof(glm::dvec2),
                               "distance cell");
        params_.assign(&setup.params, sizeof(shared::PenumbraLutParams), "parameter");
        reserved_params_ = setup.params;
        reserved_certified_ = setup.options.certified;
        reserved_ = true;
    }

    /// Load-time check of the range a later generate(setup, table) writes (GL queries; throws
    /// penumbra::Error naming the problem): setup reserved, `table` a buffer with storage, inside
    /// GL_BUFFER_SIZE, offset a multiple of GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, holding
    /// setup.tableBytes().
    void validate(const LightLutSetup& setup, const BufferRange& table) const {
        PENUMBRA_CHECK(matches(setup), "penumbra::LightLutGenerator::validate: the setup is not the one reserve() "
                                       "uploaded (call reserve(setup) at load time)");
        gl::validateRange(table, setup.tableBytes(), "table", "LightLutGenerator::validate", ssbo_alignment_);
    }

    /// Per call: writes the whole LUT of `setup` (the one reserve() uploaded) into `table`. See
    /// the Status list and the GL state contract at the top of this file.
    Status generate(const LightLutSetup& setup, const BufferRange& table) {
        if (!matches(setup)) {
            PENUMBRA_ASSERT(matches(setup) && "penumbra::LightLutGenerator::generate: setup not reserved");
            return Status::NotReserved;
        }
        if (!table.holds(setup.tableBytes())) {
            PENUMBRA_ASSERT(table.holds(setup.tableBytes()) && "penumbra::LightLutGenerator::generate: table range too small");
            return Status::RangeTooSmall;
        }
        if (table.offset % ssbo_alignment_ != 0) {
            PENUMBRA_ASSERT(table.offset % ssbo_alignment_ == 0 &&
                            "penumbra::LightLutGenerator::generate: table offset breaks the SSBO offset alignment");
            return Status::Misaligned;
        }
        const shared::PenumbraLutParams& p = reserved_params_;
        const uint64_t cells = uint64_t(p.resolution_normal) * p.resolution_normal;
        bindRange(GL_UNIFORM_BUFFER, bindings_.params, params_.id(), 0, sizeof(shared::PenumbraLutParams));
        bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.normal_cells, normal_cells_.id(), 0, cells * sizeof(glm::dvec4));
        bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.distance_cells, distance_cells_.id(), 0,
                  uint64_t(p.resolution_distance) * sizeof(glm::dvec2));
        glUseProgram(program_.id());
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        for (const LightLutDispatch& d : dispatches_) {
            const uint64_t first_texel = uint64_t(d.first_table) * p.texels_per_table + uint64_t(d.first_k) * cells;
            const uint64_t window = d.k_count == p.resolution_distance ? uint64_t(d.tables) * p.texels_per_table
                                                                       : uint64_t(d.k_count) * cells;
            bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.samples, samples_.id(), uint64_t(d.first_table) * 128u * 32u,
                      uint64_t(d.tables) * 128u * 32u);
            bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.table, table.buffer, table.offset + first_texel * 16u,
                      window * 16u);
            if (reserved_certified_) {
                bindRange(GL_SHADER_STORAGE_BUFFER, bindings_.uncertain, table.buffer,
                          table.offset + (uint64_t(p.uncertain_offset) + first_texel) * 16u, window * 16u);
            }
            glProgramUniform4ui(program_.id(), 0, d.first_table, d.first_k, d.k_count, static_cast<GLuint>(d.groups));
            glDispatchCompute(d.grid_x, d.grid_y, 1);
        }
        return Status::Ok;
    }

    /// The dispatches generate() issues for the reserved setup (empty before reserve()).
    const std::vector<LightLutDispatch>& dispatches() const { return dispatches_; }
    bool reserved() const { return reserved_; }
    const LightLutBindings& bindings() const { return bindings_; }
    GLuint program() const { return program_.id(); }
    /// GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT: the table offset's alignment.
    uint32_t tableAlignment() const { return ssbo_alignment_; }
    /// Bytes of GPU memory the generator holds (its input and parameter buffers).
    uint64_t ownedBytes() const {
        return samples_.bytes() + normal_cells_.bytes() + distance_cells_.bytes() + params_.bytes();
    }

private:
    LightLutBindings bindings_;
    uint64_t max_binding_bytes_ = 0, max_x_ = 0, max_y_ = 0;
    uint32_t ssbo_alignment_ = 1;
    gl::Program program_;
    detail::LutOwnedBuffer samples_, normal_cells_, distance_cells_, params_;
    std::vector<LightLutDispatch> dispatches_;
    shared::PenumbraLutParams reserved_params_{};
    bool reserved_certified_ = false;
    bool reserved_ = false;

    bool matches(const LightLutSetup& s) const {
        return reserved_ && std::memcmp(&s.params, &reserved_params_, sizeof reserved_params_) == 0 &&
               s.options.certified == reserved_certified_ && s.samples.size() == size_t(reserved_params_.tables) * 128u &&
               s.normal_cells.size() == size_t(reserved_params_.resolution_normal) * reserved_params_.resolution_normal &&
               s.distance_cells.size() == reserved_params_.resolution_distance;
    }

    static void bindRange(GLenum target, GLuint index, GLuint buffer, uint64_t offset, uint64_t size) {
        const GLintptr o = static_cast<GLintptr>(offset);
        const GLsizeiptr s = static_cast<GLsizeiptr>(size);
        glBindBuffersRange(target, index, 1, &buffer, &o, &s);
    }

    std::array<gl::BlockBinding, 5> storageBlocks() const {
        return {{{"samples", "PenumbraLutSamplesBlock", bindings_.samples},
                 {"normal_cells", "PenumbraLutNormalCellsBlock", bindings_.normal_cells},
                 {"distance_cells", "PenumbraLutDistanceCellsBlock", bindings_.distance_cells},
                 {"table", "PenumbraLutCentreBlock", bindings_.table},
                 {"uncertain", "PenumbraLutUncertainBlock", bindings_.uncertain}}};
    }

    void checkBindings() const {
        const auto storage = storageBlocks();
        gl::checkBlockBindings("LightLutBindings", storage.data(), int(storage.size()), "params", bindings_.params);
    }

    // Re-points the program's blocks at bindings_ (program state, set once at construction).
    void pointBlocks(GLuint program) const {
        const auto storage = storageBlocks();
        gl::pointBlocks(program, storage.data(), int(storage.size()), "PenumbraLutParamsBlock", bindings_.params);
    }
};

/// Reads the whole LUT back (waits for the GPU; tests and tools): setup.texelCount() * 4 words.
/// Issues glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT) first. Throws penumbra::Error when the
/// range is too small.
inline std::vector<uint32_t> readLightLut(const LightLutSetup& setup, const BufferRange& table) {
    PENUMBRA_CHECK(table.holds(setup.tableBytes()), "penumbra::readLightLut: the range holds ", table.size,
                   " bytes, the LUT has ", setup.tableBytes());
    std::vector<uint32_t> words(static_cast<size_t>(setup.texelCount() * 4u));
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    if (!words.empty()) {
        glGetNamedBufferSubData(table.buffer, static_cast<GLintptr>(table.offset),
                                static_cast<GLsizeiptr>(setup.tableBytes()), words.data());
    }
    return words;
}

/// A GL_TEXTURE_3D with immutable RGBA32UI storage of one table (R_n x R_n x R_d, one level,
/// nearest filtering, clamped): texel (i, j, k) = uvec4 (k * R_n + j) * R_n + i of the table.
inline gl::Texture createLightLutTexture(const LightLutSetup& setup) {
    gl::Texture texture(GL_TEXTURE_3D);
    const auto& p = setup.params;
    glTextureStorage3D(texture.id(), 1, GL_RGBA32UI, static_cast<GLsizei>(p.resolution_normal),
                       static_cast<GLsizei>(p.resolution_normal), static_cast<GLsizei>(p.resolution_distance));
    glTextureParameteri(texture.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(texture.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        glTextureParameteri(texture.id(), wrap, GL_CLAMP_TO_EDGE);
    return texture;
}

/// Setup helper: copies table `index`'s centre (or, certified, uncertain) masks from the LUT in
/// `table` into `texture` (createLightLutTexture storage) on the GPU, through the pixel-unpack
/// buffer binding. Queries and restores GL_PIXEL_UNPACK_BUFFER_BINDING and the GL_UNPACK_* state it
/// sets; issues glMemoryBarrier(GL_PIXEL_BUFFER_BARRIER_BIT) first. Throws penumbra::Error for a
/// table index out of range, uncertain masks of a seed-mode LUT or a range too small.
inline void uploadLightLutTexture(GLuint texture, const LightLutSetup& setup, const BufferRange& table, uint32_t index,
                                  bool uncertain = false) {
    const auto& p = setup.params;
    PENUMBRA_CHECK(index < p.tables, "penumbra::uploadLightLutTexture: table ", index, " of ", p.tables);
    PENUMBRA_CHECK(!uncertain || setup.options.certified,
                   "penumbra::uploadLightLutTexture: a seed-mode LUT has no uncertain masks");
    PENUMBRA_CHECK(table.holds(setup.tableBytes()), "penumbra::uploadLightLutTexture: the range holds ", table.size,
                   " bytes, the LUT has ", setup.tableBytes());
    const uint64_t first = (uncertain ? uint64_t(p.uncertain_offset) : 0u) + uint64_t(index) * p.texels_per_table;
    const GLenum names[] = {GL_UNPACK_ROW_LENGTH, GL_UNPACK_IMAGE_HEIGHT, GL_UNPACK_SKIP_ROWS,
                            GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SKIP_IMAGES, GL_UNPACK_ALIGNMENT};
    GLint saved[6];
    for (int i = 0; i < 6; ++i) saved[i] = gl::getInteger(names[i]);
    const GLint previous = gl::getInteger(GL_PIXEL_UNPACK_BUFFER_BINDING);
    for (int i = 0; i < 5; ++i) glPixelStorei(names[i], 0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glMemoryBarrier(GL_PIXEL_BUFFER_BARRIER_BIT);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, table.buffer);
    glTextureSubImage3D(texture, 0, 0, 0, 0, static_cast<GLsizei>(p.resolution_normal),
                        static_cast<GLsizei>(p.resolution_normal), static_cast<GLsizei>(p.resolution_distance),
                        GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                        reinterpret_cast<const void*>(static_cast<uintptr_t>(table.offset + first * 16u)));
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, static_cast<GLuint>(previous));
    for (int i = 0; i < 6; ++i) glPixelStorei(names[i], saved[i]);
}

}  // namespace penumbra

#endif
