# ctest `gpu_bundle`: builds the real-GPU bundle from this build (tools/gpu_bundle.sh with
# PENUMBRA_BUNDLE_NO_BUILD=1: ctest runs after `all`, which builds every bundled target) and runs
# its `run.sh --smoke` on llvmpipe in a cleared environment (no LD_LIBRARY_PATH, a minimal PATH),
# as on a machine that has only the GL driver: a missing library, a path into this checkout or a
# stale step list fails here instead of on the GPU machine.
#   -DPENUMBRA_SOURCE_DIR= -DPENUMBRA_BUILD_DIR= -DBUNDLE_DIR= -DOUT_DIR=
foreach(var PENUMBRA_SOURCE_DIR PENUMBRA_BUILD_DIR BUNDLE_DIR OUT_DIR)
    if(NOT DEFINED ${var})
        message(FATAL_ERROR "run_bundle.cmake: -D${var}= is required")
    endif()
endforeach()

execute_process(COMMAND ${CMAKE_COMMAND} -E env PENUMBRA_BUILD_DIR=${PENUMBRA_BUILD_DIR} PENUMBRA_BUNDLE_NO_BUILD=1
                        ${PENUMBRA_SOURCE_DIR}/tools/gpu_bundle.sh ${BUNDLE_DIR}
                RESULT_VARIABLE bundle_result)
if(NOT bundle_result EQUAL 0)
    message(FATAL_ERROR "tools/gpu_bundle.sh failed (${bundle_result})")
endif()

# env -i: nothing of this shell reaches run.sh (LD_LIBRARY_PATH, PENUMBRA_*, the build's PATH);
# HOME only because Mesa's shader cache wants one.
set(home "$ENV{HOME}")
if(home STREQUAL "")
    set(home "/tmp")
endif()
file(REMOVE_RECURSE "${OUT_DIR}")
execute_process(COMMAND env -u LD_LIBRARY_PATH -i PATH=/usr/bin:/bin HOME=${home}
                        ${BUNDLE_DIR}/run.sh --smoke ${OUT_DIR}
                RESULT_VARIABLE run_result)
if(NOT run_result EQUAL 0)
    message(FATAL_ERROR "${BUNDLE_DIR}/run.sh --smoke failed (${run_result}); see ${OUT_DIR}/summary.txt and its logs")
endif()
foreach(file summary.txt summary.json gl_info.json)
    if(NOT EXISTS "${OUT_DIR}/${file}")
        message(FATAL_ERROR "run.sh --smoke wrote no ${OUT_DIR}/${file}")
    endif()
endforeach()
message(STATUS "gpu_bundle: run.sh --smoke passed; results in ${OUT_DIR}")
