// penumbra — lets C++ include the `*_shared.h` files that GLSL also includes (STYLE.md habit 2):
// GLSL scalar and vector type names map to GLM, so a struct declared once has the same layout on
// both sides. Host code static_asserts the sizes the shaders assume.
#ifndef PENUMBRA_DETAIL_SHARED_HPP
#define PENUMBRA_DETAIL_SHARED_HPP

#include <glm/glm.hpp>

#include <cstdint>

namespace penumbra::shared {
using uint = std::uint32_t;
using uvec2 = glm::uvec2;
using uvec4 = glm::uvec4;
using ivec2 = glm::ivec2;
using ivec4 = glm::ivec4;
using vec2 = glm::vec2;
using vec4 = glm::vec4;
using mat4 = glm::mat4;
using dvec2 = glm::dvec2;
using dvec4 = glm::dvec4;
}  // namespace penumbra::shared

#endif
