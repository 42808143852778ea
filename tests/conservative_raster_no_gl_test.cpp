// penumbra/conservative_raster.hpp is GL-free: setup, plan, CPU twins and the exact pixel
// predicate compile and run with no GL header anywhere in the translation unit (and no
// <regex>/<filesystem>: ShaderDefines comes from penumbra/shader_defines.hpp).
#include <penumbra/conservative_raster.hpp>

#if defined(GL_VERSION_1_0) || defined(__gl_h_) || defined(__glad_h_) || defined(GLAD_GL_H_) || defined(__gl_glcorearb_h_) || defined(__glext_h_) || defined(__gl_glext_h_) || defined(__EPOXY_GL_H)
#error penumbra/conservative_raster.hpp pulled in a GL header
#endif
#if defined(PENUMBRA_SHADER_SOURCE_HPP)
#error penumbra/conservative_raster.hpp pulled in the shader assembler (regex, filesystem)
#endif
#if defined(__GLIBCXX__) && (defined(_GLIBCXX_REGEX) || defined(_GLIBCXX_FILESYSTEM))
#error penumbra/conservative_raster.hpp pulled in <regex> or <filesystem>
#endif

#include <doctest/doctest.h>

TEST_CASE("cpu: conservative_raster.hpp needs no GL header: setup, plan, twin and predicate run") {
    penumbra::ConservativeRasterOptions o;
    o.viewport_width = 16;
    o.viewport_height = 16;
    o.max_triangles = 1000;
    const penumbra::ConservativeRasterSetup setup = penumbra::conservativeRasterSetup(o);
    CHECK(setup.spill.enabled);
    CHECK(setup.spill.capacity == 1000u);
    CHECK(setup.spill.buffer_bytes == 32u + 64u * 1000u);
    CHECK(setup.spill.direct_max_vertices == 6);
    const glm::vec4 a(-0.5f, -0.5f, 0, 1), b(0.5f, -0.5f, 0, 1), c(0, 0.5f, 0, 1);
    const penumbra::ConservativeHull hull = penumbra::conservativeHull(a, b, c, setup);
    CHECK(hull.kind == penumbra::ConservativeHullKind::Triangle);
    CHECK(hull.count == 6);
    CHECK_FALSE(penumbra::conservativeNeedsSpill(a, b, c, setup));
    CHECK(penumbra::conservativeNeedsSpill(a, b, glm::vec4(0, 0.5f, -3, 1), setup));
    CHECK(!penumbra::conservativeRequiredPixels(a, b, c, setup).empty());
    CHECK(!penumbra::rasterizeConservativeHull(hull, setup).fragments.empty());
}
