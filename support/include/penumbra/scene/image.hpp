// penumbra::scene image helpers — an RGB8 image, linear float -> sRGB8, and PNG writing.
// Part of penumbra::support (support/include/; a core install has none of it, see CMakeLists.txt:
// PENUMBRA_BUILD_SUPPORT). CMake target penumbra::support links tinyobjloader and stb.
//
// Integration: needs stb_image_write.h (Debian/Ubuntu: libstb-dev). The stb functions must be
// compiled once per program, one of two ways:
//   - link the distribution's libstb (Debian: -lstb, pkg-config `stb`), which already holds them;
//   - or define PENUMBRA_IMAGE_IMPLEMENTATION in exactly one .cpp before including this header,
//     which compiles stb_image_write's implementation into that file (then do not link libstb).
// The header is found as <stb_image_write.h> or <stb/stb_image_write.h>; define
// PENUMBRA_STB_IMAGE_WRITE_HEADER (e.g. "third_party/stb_image_write.h") to point elsewhere.
// Produces PNG files or bytes; failures throw penumbra::Error naming the path or the bad value.
#ifndef PENUMBRA_SCENE_IMAGE_HPP
#define PENUMBRA_SCENE_IMAGE_HPP

#include <penumbra/error.hpp>

#if defined(PENUMBRA_IMAGE_IMPLEMENTATION) && !defined(STB_IMAGE_WRITE_IMPLEMENTATION)
#define STB_IMAGE_WRITE_IMPLEMENTATION
#endif

// stb is third-party C: keep the engine's warning flags from firing inside it.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#if defined(__clang__)
#pragma GCC diagnostic ignored "-Wunknown-warning-option"
#else
#pragma GCC diagnostic ignored "-Wpragmas"
#endif
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wdouble-promotion"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wcast-qual"
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wuseless-cast"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#endif
#if defined(PENUMBRA_STB_IMAGE_WRITE_HEADER)
#include PENUMBRA_STB_IMAGE_WRITE_HEADER
#elif __has_include(<stb_image_write.h>)
#include <stb_image_write.h>
#elif __has_include(<stb/stb_image_write.h>)
#include <stb/stb_image_write.h>
#else
#error "penumbra/scene/image.hpp needs stb_image_write.h (libstb-dev) or PENUMBRA_STB_IMAGE_WRITE_HEADER"
#endif
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace penumbra::scene {

/// 8-bit RGB image: pixels holds width * height * 3 bytes, rows top to bottom, no padding.
struct ImageRgb8 {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> pixels;
};

/// A width x height image filled with `rgb` (black by default).
inline ImageRgb8 makeImageRgb8(uint32_t width, uint32_t height, uint8_t r = 0, uint8_t g = 0,
                               uint8_t b = 0);

/// Linear [0, 1] -> sRGB-encoded byte (IEC 61966-2-1 curve, rounded to nearest). Values <= 0
/// and NaN give 0, values >= 1 give 255: shading results can be written without pre-clamping.
inline uint8_t linearToSrgb8(float linear);

/// sRGB-encoded byte -> linear [0, 1]; inverse of linearToSrgb8 on all 256 codes.
inline float srgb8ToLinear(uint8_t srgb);

/// Converts width * height linear float pixels with `channels` = 1 (grey) or 3 (RGB) values each
/// to sRGB8. bottom_up = true reads row 0 as the bottom row, as glReadPixels returns it.
/// Throws penumbra::Error for channels other than 1 or 3, a null `values` with a nonzero size,
/// or a size overflow.
inline ImageRgb8 imageFromLinear(uint32_t width, uint32_t height, const float* values,
                                 uint32_t channels, bool bottom_up = false);

/// Reverses the row order in place (bottom-up GL readbacks <-> top-down images).
/// Throws penumbra::Error if pixels.size() != width * height * 3.
inline void flipRows(ImageRgb8& image);

/// The image as PNG file bytes. Throws penumbra::Error for an empty image, a pixel count that
/// does not match width * height * 3, or a row too wide for stb (3 * width > INT_MAX).
inline std::vector<uint8_t> encodePng(const ImageRgb8& image);

/// Writes the image as a PNG file; throws penumbra::Error naming the path when the image is
/// invalid (see encodePng) or the file cannot be created or written.
inline void writePng(const std::string& path, const ImageRgb8& image);

// =============================================================================================
// Implementation

namespace detail {

inline void checkImageShape(const char* function, const ImageRgb8& image) {
    const uint64_t expected = uint64_t(image.width) * image.height * 3u;
    PENUMBRA_CHECK(image.pixels.size() == expected, "penumbra::scene::", function, ": a ",
                   image.width, "x", image.height, " RGB8 image needs ", expected,
                   " bytes, pixels holds ", image.pixels.size());
}

}  // namespace detail

inline ImageRgb8 makeImageRgb8(uint32_t width, uint32_t height, uint8_t r, uint8_t g, uint8_t b) {
    const uint64_t count = uint64_t(width) * height;
    PENUMBRA_CHECK(count * 3u <= SIZE_MAX, "penumbra::scene::makeImageRgb8: ", width, "x", height,
                   " is too large");
    ImageRgb8 image;
    image.width = width;
    image.height = height;
    image.pixels.resize(static_cast<size_t>(count * 3u));
    for (size_t i = 0; i < image.pixels.size(); i += 3) {
        image.pixels[i] = r;
        image.pixels[i + 1] = g;
        image.pixels[i + 2] = b;
    }
    return image;
}

inline uint8_t linearToSrgb8(float linear) {
    if (!(linear > 0.0f)) return 0;  // also catches NaN
    if (linear >= 1.0f) return 255;
    const float encoded = linear <= 0.0031308f ? 12.92f * linear
                                               : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
    return static_cast<uint8_t>(std::min(255.0f, encoded * 255.0f + 0.5f));
}

inline float srgb8ToLinear(uint8_t srgb) {
    const float encoded = static_cast<float>(srgb) / 255.0f;
    return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

inline ImageRgb8 imageFromLinear(uint32_t width, uint32_t height, const float* values,
                                 uint32_t channels, bool bottom_up) {
    PENUMBRA_CHECK(channels == 1 || channels == 3,
                   "penumbra::scene::imageFromLinear: channels must be 1 or 3, got ", channels);
    ImageRgb8 image = makeImageRgb8(width, height);
    PENUMBRA_CHECK(values != nullptr || image.pixels.empty(),
                   "penumbra::scene::imageFromLinear: values is null for a ", width, "x", height,
                   " image");
    for (uint32_t y = 0; y < height; ++y) {
        const uint32_t source_row = bottom_up ? height - 1 - y : y;
        const float* row = values + size_t(source_row) * width * channels;
        uint8_t* out = image.pixels.data() + size_t(y) * width * 3;
        for (uint32_t x = 0; x < width; ++x) {
            for (uint32_t c = 0; c < 3; ++c)
                out[3 * x + c] = linearToSrgb8(row[size_t(x) * channels + (channels == 3 ? c : 0)]);
        }
    }
    return image;
}

inline void flipRows(ImageRgb8& image) {
    detail::checkImageShape("flipRows", image);
    const size_t stride = size_t(image.width) * 3;
    for (uint32_t top = 0, bottom = image.height; top + 1 < bottom; ++top, --bottom) {
        std::swap_ranges(image.pixels.begin() + static_cast<std::ptrdiff_t>(top * stride),
                         image.pixels.begin() + static_cast<std::ptrdiff_t>((top + 1) * stride),
                         image.pixels.begin() + static_cast<std::ptrdiff_t>((bottom - 1) * stride));
    }
}

inline std::vector<uint8_t> encodePng(const ImageRgb8& image) {
    PENUMBRA_CHECK(image.width > 0 && image.height > 0,
                   "penumbra::scene::encodePng: image is empty (", image.width, "x", image.height,
                   ")");
    detail::checkImageShape("encodePng", image);
    PENUMBRA_CHECK(uint64_t(image.width) * 3u <= uint64_t(INT_MAX) && image.height <= uint32_t(INT_MAX),
                   "penumbra::scene::encodePng: ", image.width, "x", image.height,
                   " exceeds stb_image_write's int sizes");
    std::vector<uint8_t> bytes;
    // Encoding to memory (rather than stbi_write_png's fopen) lets writePng report the OS error.
    auto append = [](void* context, void* data, int size) {
        auto* out = static_cast<std::vector<uint8_t>*>(context);
        const auto* first = static_cast<const uint8_t*>(data);
        out->insert(out->end(), first, first + size);
    };
    const int ok = stbi_write_png_to_func(append, &bytes, static_cast<int>(image.width),
                                          static_cast<int>(image.height), 3, image.pixels.data(),
                                          static_cast<int>(image.width * 3u));
    PENUMBRA_CHECK(ok != 0 && !bytes.empty(), "penumbra::scene::encodePng: stb_image_write failed for a ",
                   image.width, "x", image.height, " image (out of memory?)");
    return bytes;
}

inline void writePng(const std::string& path, const ImageRgb8& image) {
    std::vector<uint8_t> bytes;
    try {
        bytes = encodePng(image);
    } catch (const Error& error) {
        ::penumbra::detail::fail("penumbra::scene::writePng('", path, "'): ", error.what());
    }
    errno = 0;
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    PENUMBRA_CHECK(file.is_open(), "penumbra::scene::writePng: cannot create '", path, "'",
                   errno != 0 ? std::string(": ") + std::strerror(errno) : std::string());
    file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    file.close();
    PENUMBRA_CHECK(!file.fail(), "penumbra::scene::writePng: cannot write ", bytes.size(),
                   " bytes to '", path, "'",
                   errno != 0 ? std::string(": ") + std::strerror(errno) : std::string());
}

}  // namespace penumbra::scene

#endif
