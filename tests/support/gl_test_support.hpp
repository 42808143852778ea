// The one headless context a GL test executable uses (created on first use, on the backend
// PENUMBRA_GL names; see penumbra/gl/headless.hpp).
#ifndef PENUMBRA_TESTS_SUPPORT_GL_TEST_SUPPORT_HPP
#define PENUMBRA_TESTS_SUPPORT_GL_TEST_SUPPORT_HPP

#include "penumbra/gl/headless.hpp"
#include "support/test_support.hpp"

namespace penumbra::test {

inline penumbra::gl::HeadlessContext& context() {
    static penumbra::gl::HeadlessContext ctx;
    return ctx;
}

}  // namespace penumbra::test

#endif
