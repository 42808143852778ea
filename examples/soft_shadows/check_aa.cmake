# Runs soft_shadows --mode hard --aa edge --reference --json (ARGS: extra flags, '|'-separated) and
# requires: the provable stencil missed no edge pixel (reference.missed_edge_pixels == 0), --aa edge
# equals --aa full in every pixel (aa.edge_vs_full_differing_pixels == 0), there were edge pixels to
# find, anti-aliasing lowered the RMSE against 64 oracle points per pixel (edge < off), and both
# images beside OUT exist. Invoked by ctest.
string(REPLACE "|" ";" extra "${ARGS}")
execute_process(COMMAND "${EXE}" --mode hard --aa edge --reference --json --out "${OUT}" ${extra}
                RESULT_VARIABLE result OUTPUT_VARIABLE json ERROR_VARIABLE err)
if(NOT result EQUAL 0)
    message(FATAL_ERROR "soft_shadows failed (${result}): ${err}")
endif()
string(JSON missed GET "${json}" reference missed_edge_pixels)
string(JSON edge_pixels GET "${json}" reference edge_pixels)
string(JSON differing GET "${json}" aa edge_vs_full_differing_pixels)
string(JSON flagged GET "${json}" aa flagged_fraction)
string(JSON rmse_off GET "${json}" aa rmse off)
string(JSON rmse_edge GET "${json}" aa rmse edge)
string(JSON compare GET "${json}" aa_compare)
string(JSON stencil GET "${json}" aa_stencil)
if(NOT missed EQUAL 0 OR NOT differing EQUAL 0 OR edge_pixels LESS 10 OR NOT rmse_edge LESS rmse_off)
    message(FATAL_ERROR "anti-aliased hard shadows: missed ${missed}, edge vs full ${differing}, edge pixels ${edge_pixels}, "
                        "RMSE off ${rmse_off} edge ${rmse_edge}: ${json}")
endif()
if(NOT EXISTS "${compare}" OR NOT EXISTS "${stencil}")
    message(FATAL_ERROR "missing image ${compare} or ${stencil}")
endif()
message("ok: ${edge_pixels} edge pixels, 0 missed, ${flagged} flagged, edge == full, RMSE off ${rmse_off} -> edge ${rmse_edge}: ${json}")
