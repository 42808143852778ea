# Runs the default and the contracted (-ffp-contract=fast -march=native) builds of
# conservative_raster_twin_bits and fails unless both print the same line.
execute_process(COMMAND "${DEFAULT}" OUTPUT_VARIABLE a RESULT_VARIABLE ra)
execute_process(COMMAND "${CONTRACTED}" OUTPUT_VARIABLE b RESULT_VARIABLE rb)
message(STATUS "default:    ${a}")
message(STATUS "contracted: ${b}")
if(NOT ra EQUAL 0 OR NOT rb EQUAL 0 OR a STREQUAL "" OR NOT a STREQUAL b)
    message(FATAL_ERROR "conservative-raster twins differ under -ffp-contract=fast -march=native")
endif()
