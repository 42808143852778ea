// penumbra — error reporting shared by every block.
//
// Setup code (sizes, options, shader assembly, GL object creation) throws penumbra::Error with a
// message that names the bad value. Hot paths only use PENUMBRA_ASSERT, which an engine may
// redefine before including any penumbra header (e.g. to its own assert or to nothing).
#ifndef PENUMBRA_ERROR_HPP
#define PENUMBRA_ERROR_HPP

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace penumbra {

/// The one exception type penumbra throws. what() is a complete, human-readable sentence.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

namespace detail {

template <typename... Args>
[[noreturn]] inline void fail(Args&&... args) {
    std::ostringstream out;
    (out << ... << std::forward<Args>(args));
    throw Error(out.str());
}

}  // namespace detail
}  // namespace penumbra

/// Throws penumbra::Error built from the streamed arguments when `cond` is false.
#define PENUMBRA_CHECK(cond, ...)                                   \
    do {                                                            \
        if (!(cond)) ::penumbra::detail::fail(__VA_ARGS__);         \
    } while (0)

#ifndef PENUMBRA_ASSERT
#include <cassert>
/// Hot-path invariant check; overridable by defining PENUMBRA_ASSERT before including penumbra.
#define PENUMBRA_ASSERT(cond) assert(cond)
#endif

#endif
