# Runs soft_shadows --check-skips --json (ARGS: the mode and extra flags, '|'-separated): the frame
# with the given --skips and again with every skip off. Every shadow word must be identical
# (skips_check.identical, mismatched_words 0), the comparison must cover the image, and in soft
# mode the skips must have removed work (fewer pairs) when every skip is on. Invoked by ctest
# (examples/CMakeLists.txt).
string(REPLACE "|" ";" extra "${ARGS}")
execute_process(COMMAND "${EXE}" --json --check-skips --out "${OUT}" ${extra}
                RESULT_VARIABLE result OUTPUT_VARIABLE json ERROR_VARIABLE err)
if(NOT result EQUAL 0)
    message(FATAL_ERROR "soft_shadows failed (${result}): ${err}")
endif()
string(JSON identical GET "${json}" skips_check identical)
string(JSON mismatched GET "${json}" skips_check mismatched_words)
string(JSON compared GET "${json}" skips_check compared_words)
if(NOT identical OR NOT mismatched EQUAL 0 OR compared EQUAL 0)
    message(FATAL_ERROR "the skips changed ${mismatched} of ${compared} shadow words: ${json}")
endif()
string(JSON mode GET "${json}" mode)
string(JSON skips LENGTH "${json}" skips)
set(work "")
if(mode STREQUAL "soft" AND skips EQUAL 4)
    string(JSON pairs_on GET "${json}" skips_check on pairs)
    string(JSON pairs_off GET "${json}" skips_check off pairs)
    if(NOT pairs_on LESS pairs_off)
        message(FATAL_ERROR "every skip on but no pair saved (${pairs_on} vs ${pairs_off}): ${json}")
    endif()
    set(work ", pairs ${pairs_on} vs ${pairs_off} with every skip off")
endif()
message("ok: ${compared} words identical${work}")
