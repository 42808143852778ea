# Generates a glad 2 GL 4.5 core loader into the build tree with Debian's python3-glad
# (`glad --reproducible` uses the Khronos XML bundled with the package: no network). Only tests,
# benchmarks and examples use it; the library itself includes whatever PENUMBRA_GL_HEADER names.
#
#   penumbra_add_glad_target(<target> [DEBUG])
# DEBUG generates glad's `c --debug` variant into build/glad_debug: every gl* call goes through
# glad's pre/post-call callbacks (gladSetGLPreCallback), which tests/support/gl_audit.hpp uses to
# record the GL calls of a per-frame executor. Link one of the two targets per executable, never
# both (same header name, same symbols).
set(PENUMBRA_GLAD_EXTENSIONS
    GL_KHR_debug GL_KHR_shader_subgroup GL_ARB_shader_ballot GL_ARB_shader_group_vote
    GL_NV_conservative_raster GL_INTEL_conservative_rasterization GL_ARB_fragment_shader_interlock)

function(penumbra_add_glad_target target)
    cmake_parse_arguments(G "DEBUG" "" "" ${ARGN})
    find_program(PENUMBRA_GLAD_EXECUTABLE NAMES glad HINTS /usr/bin NO_CACHE)
    if(NOT PENUMBRA_GLAD_EXECUTABLE)
        message(FATAL_ERROR "penumbra: the glad 2 generator was not found; install Debian's python3-glad "
                            "(tools/setup.sh does)")
    endif()
    set(out "${CMAKE_BINARY_DIR}/glad")
    set(generator_options)
    if(G_DEBUG)
        set(out "${CMAKE_BINARY_DIR}/glad_debug")
        set(generator_options --debug)
    endif()
    list(JOIN PENUMBRA_GLAD_EXTENSIONS "," extensions)
    set(args --quiet --reproducible --api gl:core=4.5 --extensions ${extensions} --out-path "${out}" c
             ${generator_options})
    set(stamp "${out}/penumbra-glad.stamp")
    set(wanted "${PENUMBRA_GLAD_EXECUTABLE};${args}")
    set(have "")
    if(EXISTS "${stamp}")
        file(READ "${stamp}" have)
    endif()
    if(NOT have STREQUAL wanted OR NOT EXISTS "${out}/src/gl.c")
        file(REMOVE_RECURSE "${out}")
        # The pyenv python3 on some PATHs lacks Debian's modules: run glad with Debian's python.
        set(python /usr/bin/python3)
        if(NOT EXISTS ${python})
            set(python "")
        endif()
        execute_process(COMMAND ${python} ${PENUMBRA_GLAD_EXECUTABLE} ${args}
                        RESULT_VARIABLE result OUTPUT_VARIABLE log ERROR_VARIABLE log)
        if(NOT result EQUAL 0 OR NOT EXISTS "${out}/src/gl.c")
            message(FATAL_ERROR "penumbra: glad failed (${result}):\n${log}")
        endif()
        file(WRITE "${stamp}" "${wanted}")
    endif()
    add_library(${target} STATIC "${out}/src/gl.c")
    target_include_directories(${target} SYSTEM PUBLIC "${out}/include")
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON LINKER_LANGUAGE C)
endfunction()
