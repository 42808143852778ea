# ctest plot_bench: a tiny smoke run of the soft-shadow benchmarks as JSON, then tools/plot_bench.py
# on it; fails unless the PNG is written. Skipped (SKIP_REGULAR_EXPRESSION "matplotlib is missing")
# where Debian's python3-matplotlib is not installed.
# cmake -DBENCH=<penumbra_bench or penumbra_bench_soft> -DPYTHON=/usr/bin/python3 -DSCRIPT=<tools/plot_bench.py>
#       -DFILTER=<regex> -DOUT=<prefix: OUT.json, OUT.png> -P plot_bench.cmake
foreach(var BENCH PYTHON SCRIPT FILTER OUT)
    if(NOT DEFINED ${var})
        message(FATAL_ERROR "plot_bench.cmake: -D${var}=... is missing")
    endif()
endforeach()
file(REMOVE "${OUT}.json" "${OUT}.png")
execute_process(COMMAND "${BENCH}" "--benchmark_filter=${FILTER}" --benchmark_min_time=0.001
                        "--benchmark_out=${OUT}.json" --benchmark_out_format=json
                RESULT_VARIABLE bench_rc)
if(NOT bench_rc EQUAL 0)
    message(FATAL_ERROR "plot_bench: ${BENCH} exited with ${bench_rc}")
endif()
file(READ "${OUT}.json" json)
string(FIND "${json}" "\"err_" has_errors)
if(has_errors EQUAL -1)
    message(FATAL_ERROR "plot_bench: ${OUT}.json has no err_* counter (filter ${FILTER} matched nothing?)")
endif()
execute_process(COMMAND "${PYTHON}" "${SCRIPT}" "${OUT}.json" -o "${OUT}.png" RESULT_VARIABLE plot_rc)
if(plot_rc EQUAL 77)
    return()  # the script printed "matplotlib is missing": the test is reported as skipped
endif()
if(NOT plot_rc EQUAL 0)
    message(FATAL_ERROR "plot_bench: ${SCRIPT} exited with ${plot_rc}")
endif()
if(NOT EXISTS "${OUT}.png")
    message(FATAL_ERROR "plot_bench: ${OUT}.png was not written")
endif()
file(SIZE "${OUT}.png" png_size)
if(png_size LESS 1000)
    message(FATAL_ERROR "plot_bench: ${OUT}.png has only ${png_size} bytes")
endif()
message(STATUS "plot_bench: ${OUT}.png (${png_size} bytes)")
