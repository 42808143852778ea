// penumbra — the single source of the library version (CMake reads these three lines).
#ifndef PENUMBRA_VERSION_HPP
#define PENUMBRA_VERSION_HPP

#define PENUMBRA_VERSION_MAJOR 0
#define PENUMBRA_VERSION_MINOR 1
#define PENUMBRA_VERSION_PATCH 0

#define PENUMBRA_VERSION (PENUMBRA_VERSION_MAJOR * 10000 + PENUMBRA_VERSION_MINOR * 100 + PENUMBRA_VERSION_PATCH)

namespace penumbra {
inline constexpr int kVersionMajor = PENUMBRA_VERSION_MAJOR;
inline constexpr int kVersionMinor = PENUMBRA_VERSION_MINOR;
inline constexpr int kVersionPatch = PENUMBRA_VERSION_PATCH;
}  // namespace penumbra

#endif
