// penumbra — one injected shader `#define` and a list of them (pure C++, no GL, no regex or
// filesystem): what a block's pure setup returns for its permutation, and what
// penumbra/shader_source.hpp's assembler injects after `#version`. Kept apart so that a block's
// GL-free setup header (e.g. penumbra/conservative_raster.hpp) does not pull in the assembler.
#ifndef PENUMBRA_SHADER_DEFINES_HPP
#define PENUMBRA_SHADER_DEFINES_HPP

#include <string>
#include <vector>

namespace penumbra {

/// One injected `#define NAME VALUE` (VALUE may be empty).
struct ShaderDefine {
    std::string name;
    std::string value;
};
using ShaderDefines = std::vector<ShaderDefine>;

}  // namespace penumbra

#endif
