# Runs soft_shadows --mode hard --reference --json (ARGS: extra flags, '|'-separated) and requires
# the GPU to agree with the oracle on every tested sample (reference.mismatched == 0). Invoked by ctest.
string(REPLACE "|" ";" extra "${ARGS}")
execute_process(COMMAND "${EXE}" --mode hard --reference --json --width 160 --height 120 --out "${OUT}" ${extra}
                RESULT_VARIABLE result OUTPUT_VARIABLE json ERROR_VARIABLE err)
if(NOT result EQUAL 0)
    message(FATAL_ERROR "soft_shadows failed (${result}): ${err}")
endif()
string(JSON samples GET "${json}" reference samples)
string(JSON mismatched GET "${json}" reference mismatched)
string(JSON input GET "${json}" hard view_samples)
if(samples LESS 1000 OR NOT mismatched EQUAL 0)
    message(FATAL_ERROR "hard shadows disagree with the oracle: ${json}")
endif()
message("ok: ${input} view samples, ${samples} tested, ${mismatched} mismatched: ${json}")
