# Runs soft_shadows --mode hpc --reference --json (ARGS: extra flags, '|'-separated): hierarchical
# penumbra casting on the CPU must agree with the oracle on every non-tie bit
# (reference.mismatched_bits == 0) with the same per-pixel light-sample sets, and write a PNG.
# Invoked by ctest.
string(REPLACE "|" ";" extra "${ARGS}")
execute_process(COMMAND "${EXE}" --mode hpc --reference --json --width 96 --height 72 --out "${OUT}" ${extra}
                RESULT_VARIABLE result OUTPUT_VARIABLE json ERROR_VARIABLE err)
if(NOT result EQUAL 0)
    message(FATAL_ERROR "soft_shadows failed (${result}): ${err}")
endif()
string(JSON total GET "${json}" reference total_bits)
string(JSON mismatched GET "${json}" reference mismatched_bits)
string(JSON ties GET "${json}" reference ties)
string(JSON streamed GET "${json}" hpc triangles_streamed)
string(JSON peak GET "${json}" hpc mask_bytes_peak)
string(JSON full GET "${json}" hpc mask_bytes_full)
if(total LESS 100000 OR streamed LESS 100)
    message(FATAL_ERROR "too little was compared: ${json}")
endif()
if(NOT mismatched EQUAL 0)
    message(FATAL_ERROR "penumbra casting disagrees with the oracle: ${json}")
endif()
file(READ "${OUT}" signature LIMIT 8 HEX)
if(NOT signature STREQUAL "89504e470d0a1a0a")
    message(FATAL_ERROR "${OUT} is not a PNG (${signature})")
endif()
message("ok: ${mismatched} mismatched of ${total} bits, ${ties} ties, ${streamed} triangles, masks ${peak} of ${full} bytes")
