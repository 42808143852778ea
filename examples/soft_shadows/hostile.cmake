# Hostile inputs (issue 41): the command line and OBJ files a new user or an attacker would try.
# Each case states its outcome: exit 2 with a message naming the flag or the file and line, exit 0
# with a result the regex checks, or exit 1 where a check the run was asked for finds a difference
# (forced by PENUMBRA_DEMO_FAULT). Included by examples/CMakeLists.txt; label `hostile`
# (`ctest -L hostile`); tools/test.sh also runs them in the ASan+UBSan build.
set(hostile_out "${CMAKE_CURRENT_BINARY_DIR}/soft_shadows_hostile")
set(hostile_objs "${hostile_out}/objs")
file(MAKE_DIRECTORY "${hostile_objs}" "${hostile_out}/folder.png")

# soft_shadows_hostile(<name> <cpu|egl> <0|1|fail> <regex> args...): cpu cases need no GL context
# (usage errors and the CPU modes); egl cases run the GPU pipelines on EGL.
function(soft_shadows_hostile name backend expect regex)
    string(REPLACE ";" "|" cli_args "${ARGN}")
    # Each case's x.* in a folder of its own: --out is probed by creating the file and removing it,
    # which a concurrent case's "nothing written" check would otherwise see.
    string(REPLACE "${hostile_out}/x" "${hostile_out}/${name}/x" cli_args "${cli_args}")
    add_test(NAME soft_shadows.hostile.${name}
             COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:soft_shadows> "-DARGS=${cli_args}" -DEXPECT=${expect}
                     "-DREGEX=${regex}" -DOUT_DIR=${hostile_out}/${name}
                     -P ${CMAKE_CURRENT_SOURCE_DIR}/soft_shadows/check_cli.cmake)
    if(backend STREQUAL "cpu")
        set(labels "cpu;example;hostile")
    else()
        set(labels "gl;egl;example;hostile")
    endif()
    set_tests_properties(soft_shadows.hostile.${name} PROPERTIES LABELS "${labels}" ENVIRONMENT "PENUMBRA_GL=egl"
                         TIMEOUT 600)
endfunction()

set(x "${hostile_out}/x.png")  # failing cases: nothing may be written there
set(small --width 32 --height 24)
set(soft_small --mode soft --width 32 --height 24 --samples 32 --lut-res 16 --grid 64)

# ---- numbers: plain decimals only, each message naming the flag ----
soft_shadows_hostile(width_hex cpu fail "--width: '0x10' is not a decimal number" --width 0x10 --out ${x})
soft_shadows_hostile(width_empty cpu fail "--width is empty \\(give a value after '='\\)" --width= --out ${x})
soft_shadows_hostile(width_space cpu fail "--width: ' 5' is not a decimal number" "--width= 5" --out ${x})
soft_shadows_hostile(width_fraction cpu fail "--width must be a whole number in \\[1, 16384\\], got '1.5'" --width 1.5 --out ${x})
soft_shadows_hostile(width_zero cpu fail "--width must be a whole number in \\[1, 16384\\], got '0'" --width 0 --out ${x})
soft_shadows_hostile(width_negative cpu fail "--width must be a whole number in \\[1, 16384\\], got '-1'" --width -1 --out ${x})
soft_shadows_hostile(width_too_big cpu fail "--width must be a whole number in \\[1, 16384\\], got '16385'" --width 16385 --out ${x})
soft_shadows_hostile(height_exponent cpu fail "--height must be a whole number in \\[1, 16384\\], got '1e9'" --height 1e9 --out ${x})
soft_shadows_hostile(width_text cpu fail "--width: 'wide' is not a decimal number" --width wide --out ${x})
soft_shadows_hostile(light_pos_double_comma cpu fail "--light-pos takes x,y,z \\(three numbers, two commas\\), got '1,,2,3'" --light-pos 1,,2,3 --out ${x})
soft_shadows_hostile(light_pos_two cpu fail "--light-pos takes x,y,z \\(three numbers, two commas\\), got '1,2'" --light-pos 1,2 --out ${x})
soft_shadows_hostile(light_pos_four cpu fail "--light-pos takes x,y,z .*got '1,2,3,4'" --light-pos 1,2,3,4 --out ${x})
soft_shadows_hostile(light_pos_empty_axis cpu fail "--light-pos y is empty in '1,,2'" --light-pos 1,,2 --out ${x})
soft_shadows_hostile(light_pos_empty cpu fail "--light-pos is empty" --light-pos= --out ${x})
soft_shadows_hostile(light_pos_inf cpu fail "--light-pos x must be finite, got 'inf'" --light-pos inf,1,1 --out ${x})
soft_shadows_hostile(light_pos_hex cpu fail "--light-pos x: '0x1' is not a decimal number" --light-pos 0x1,1,1 --out ${x})
soft_shadows_hostile(light_pos_semicolons cpu fail "--light-pos takes x,y,z" "--light-pos=1 2 3" --out ${x})
soft_shadows_hostile(radius_denormal cpu fail "--light-radius is too small to represent .*got '1e-310'" --light-radius 1e-310 --out ${x})
soft_shadows_hostile(radius_underflow cpu fail "--light-radius is too small to represent .*got '1e-400'" --light-radius 1e-400 --out ${x})
soft_shadows_hostile(radius_overflow cpu fail "--light-radius is too large for a double, got '1e400'" --light-radius 1e400 --out ${x})
soft_shadows_hostile(radius_inf cpu fail "--light-radius must be finite, got 'inf'" --light-radius inf --out ${x})
soft_shadows_hostile(radius_minus_nan cpu fail "--light-radius must be finite, got '-nan'" --light-radius -nan --out ${x})
soft_shadows_hostile(radius_text cpu fail "--light-radius: 'abc' is not a decimal number" --light-radius abc --out ${x})
soft_shadows_hostile(radius_trailing cpu fail "--light-radius: '0.1x' is not a decimal number" --light-radius 0.1x --out ${x})
soft_shadows_hostile(radius_two_dots cpu fail "--light-radius: '1.2.3' is not a decimal number" --light-radius 1.2.3 --out ${x})
soft_shadows_hostile(radius_bare_exponent cpu fail "--light-radius: '1e' is not a decimal number" --light-radius 1e --out ${x})
soft_shadows_hostile(radius_dot cpu fail "--light-radius: '.' is not a decimal number" --light-radius . --out ${x})
soft_shadows_hostile(radius_sign cpu fail "--light-radius: '\\+' is not a decimal number" --light-radius + --out ${x})
soft_shadows_hostile(radius_zero_negative cpu fail "--light-radius must be > 0, got '-0'" --light-radius -0 --out ${x})
soft_shadows_hostile(samples_zero cpu fail "--samples must be a whole number in \\[1, 65536\\], got '0'" --samples 0 --out ${x})
soft_shadows_hostile(samples_too_many cpu fail "--samples must be a whole number in \\[1, 65536\\], got '65537'" --samples 65537 --out ${x})
soft_shadows_hostile(soft_samples_33 cpu fail "--samples must be a multiple of 32 in \\[32, 1024\\], got '33'" --mode soft --samples 33 --out ${x})
soft_shadows_hostile(soft_sets_65 cpu fail "--sets must be a whole number in \\[1, 64\\], got '65'" --mode soft --sets 65 --out ${x})
soft_shadows_hostile(soft_grid_15 cpu fail "--grid must be a whole number in \\[16, 4096\\], got '15'" --mode soft --grid 15 --out ${x})
soft_shadows_hostile(soft_grid_4097 cpu fail "--grid must be a whole number in \\[16, 4096\\], got '4097'" --mode soft --grid 4097 --out ${x})
soft_shadows_hostile(soft_rotations_0 cpu fail "--rotations must be a whole number in \\[1, 256\\], got '0'" --mode soft --rotations 0 --out ${x})
soft_shadows_hostile(soft_rotations_257 cpu fail "--rotations must be a whole number in \\[1, 256\\], got '257'" --mode soft --rotations 257 --out ${x})
soft_shadows_hostile(soft_lut_res_14 cpu fail "--lut-res must be a whole number in \\[16, 256\\], got '14'" --mode soft --lut-res 14 --out ${x})
soft_shadows_hostile(soft_lut_res_258 cpu fail "--lut-res must be a whole number in \\[16, 256\\], got '258'" --mode soft --lut-res 258 --out ${x})
soft_shadows_hostile(frames_0 cpu fail "--frames must be a whole number in \\[1, 1024\\], got '0'" --frames 0 --out ${x})
soft_shadows_hostile(frames_1025 cpu fail "--frames must be a whole number in \\[1, 1024\\], got '1025'" --frames 1025 --out ${x})
soft_shadows_hostile(frames_reference_0 cpu fail "--frames-reference must be a whole number in \\[1, 65536\\], got '0'" --frames-reference 0 --out ${x})
soft_shadows_hostile(dsm_res_4097 cpu fail "--dsm-res 4097 .*rejected: .*resolution 4097" --mode dsm --dsm-res 4097 --out ${x})
soft_shadows_hostile(dsm_samples_0 cpu fail "--dsm-samples 0 .*rejected" --mode dsm --dsm-samples 0 --out ${x})
soft_shadows_hostile(dsm_samples_fraction cpu fail "--dsm-samples must be a whole number, got '2.5'" --mode dsm --dsm-samples 2.5 --out ${x})
soft_shadows_hostile(dsm_tolerance_negative cpu fail "--tolerance -1 rejected" --mode dsm --tolerance -1 --out ${x})
soft_shadows_hostile(dsm_tolerance_nan cpu fail "--tolerance must be finite, got 'nan'" --mode dsm --tolerance nan --out ${x})
soft_shadows_hostile(dsm_opacity_negative cpu fail "--opacity must be in \\[0, 1\\].*got '-0.1'" --mode dsm --opacity -0.1 --out ${x})
soft_shadows_hostile(dsm_opacity_hex cpu fail "--opacity: '0x0.8' is not a decimal number" --mode dsm --opacity 0x0.8 --out ${x})
soft_shadows_hostile(fog_zero cpu fail "--fog needs 0 < SIGMA_S <= SIGMA_T.*got '0,0'" --mode volumetric --fog 0,0 --out ${x})
soft_shadows_hostile(fog_text cpu fail "--fog's SIGMA_S: 'a' is not a decimal number" --mode volumetric --fog a,b --out ${x})
soft_shadows_hostile(fog_three cpu fail "--fog takes SIGMA_S,SIGMA_T .*got '1,2,3'" --mode volumetric --fog 1,2,3 --out ${x})
soft_shadows_hostile(sm_res_0 cpu fail "--sm-res must be a whole number in \\[2, 4096\\], got '0'" --mode volumetric --sm-res 0 --out ${x})
soft_shadows_hostile(sm_res_8192 cpu fail "--sm-res must be a whole number in \\[2, 4096\\], got '8192'" --mode volumetric --sm-res 8192 --out ${x})
soft_shadows_hostile(aa_samples_0 cpu fail "--aa-samples must be 4, 8 or 16, got '0'" --mode hard --aa edge --aa-samples 0 --out ${x})
soft_shadows_hostile(aa_samples_text cpu fail "--aa-samples: 'four' is not a decimal number" --mode hard --aa edge --aa-samples four --out ${x})

# ---- words and paths ----
soft_shadows_hostile(skips_bogus cpu fail "--skips: 'bogus' is not a skip of --mode soft" --mode soft --skips bogus --out ${x})
soft_shadows_hostile(skips_reference_mode cpu fail "--skips is not used by --mode reference" --skips none --out ${x})
soft_shadows_hostile(skips_comma cpu fail "--skips: ',' has an empty name" --mode soft --skips , --out ${x})
soft_shadows_hostile(skips_trailing_comma cpu fail "--skips: 'fit,' has an empty name" --mode soft --skips fit, --out ${x})
soft_shadows_hostile(skips_hard_name_in_soft cpu fail "--skips: 'shadowed' is not a skip of --mode soft" --mode soft --skips shadowed --out ${x})
soft_shadows_hostile(skips_soft_name_in_hard cpu fail "--skips: 'silhouette' is not a skip of --mode hard" --mode hard --skips silhouette --out ${x})
soft_shadows_hostile(mode_empty cpu fail "--mode" --mode= --out ${x})
soft_shadows_hostile(mode_upper cpu fail "--mode" --mode SOFT --out ${x})
soft_shadows_hostile(lut_bogus cpu fail "--lut" --mode soft --lut approximate --out ${x})
soft_shadows_hostile(view_samples_bogus cpu fail "--view-samples" --mode soft --view-samples gbuffer --out ${x})
soft_shadows_hostile(positional cpu fail "stray" stray --out ${x})
soft_shadows_hostile(out_empty cpu fail "--out is empty" --out=)
soft_shadows_hostile(out_folder cpu fail "--out '.*folder.png' is a folder" --out ${hostile_out}/folder.png)
soft_shadows_hostile(out_unwritable cpu fail "--out '/proc/x.png' cannot be created" --out /proc/x.png)
soft_shadows_hostile(out_upper_extension cpu fail "unknown extension '.PNGX'" --out ${hostile_out}/x.PNGX)
soft_shadows_hostile(scene_builtin_unknown cpu fail "--scene 'builtin:nope' cannot be loaded" --scene builtin:nope --out ${x})
soft_shadows_hostile(scene_missing cpu fail "--scene '/nonexistent/x.obj' cannot be loaded: .*cannot open file" --scene /nonexistent/x.obj --out ${x})
soft_shadows_hostile(scene_folder cpu fail "--scene '.*objs' cannot be loaded" --scene ${hostile_objs} --out ${x})
soft_shadows_hostile(check_skips_reference cpu fail "--check-skips is not used by --mode reference" --check-skips --out ${x})
soft_shadows_hostile(check_skips_aa cpu fail "--check-skips is not used with --aa edge" --mode hard --aa edge --check-skips --out ${x})

# ---- lights and origins ----
soft_shadows_hostile(light_inside_scene cpu fail "the light's centre \\(0, 0.3, 0\\) lies inside the scene's bounds.*move it with --light-pos" --light-pos 0,0.3,0 --out ${x})
soft_shadows_hostile(soft_light_inside_scene cpu fail "lies inside the scene's bounds" --mode soft --light-pos 0.5,0.5,0.5 --out ${x})
soft_shadows_hostile(hard_light_inside egl fail "--light-pos \\(0, 0.3.*cannot light the view samples from there: .*lies inside or beside the box" --mode hard --light-pos 0,0.3,0 ${small} --out ${x})
soft_shadows_hostile(radius_reaches_scene cpu fail "reaches into the scene: its centre is .* from the scene's bounds" --light-pos 0,3,0 --light-radius 2.5 --out ${x})
soft_shadows_hostile(origin_1e15 cpu fail "--origin \\(1e\\+15, 0, 0\\) is beyond the range this scene supports: .*2\\^26" --origin 1e15,0,0 --out ${x})
soft_shadows_hostile(origin_1e30_hpc cpu fail "--origin \\(1e\\+30, 0, 0\\) is beyond the range" --mode hpc --origin 1e30,0,0 --out ${x})
soft_shadows_hostile(origin_negative_far cpu fail "--origin \\(0, -1e\\+10, 0\\) is beyond the range" --mode soft --origin 0,-1e10,0 --out ${x})
soft_shadows_hostile(origin_nan cpu fail "--origin x must be finite, got 'nan'" --origin nan,0,0 --out ${x})
soft_shadows_hostile(origin_text cpu fail "--origin z: 'x' is not a decimal number" --origin 1,2,x --out ${x})

# ---- documented-valid sizes and lights that used to fail: they work, results checked ----
soft_shadows_hostile(hard_1x1 egl 0 "\"view_samples\":1,.*\"reference\":\\{\"samples\":1,\"mismatched\":0"
                     --mode hard --width 1 --height 1 --reference --json --out ${hostile_out}/hard_1x1.png)
soft_shadows_hostile(soft_1x1 egl 0 "\"view_samples\":1,.*\"mismatched_bits\":0,"
                     --mode soft --width 1 --height 1 --samples 32 --lut-res 16 --grid 16 --reference --json
                     --out ${hostile_out}/soft_1x1.png)
soft_shadows_hostile(reference_1x1 cpu 0 "\"view_samples\":1,.*\"mean_visible_fraction\":"
                     --width 1 --height 1 --samples 4 --json --out ${hostile_out}/reference_1x1.png)
soft_shadows_hostile(hpc_1x1 cpu 0 "\"view_samples\":1,.*\"mismatched_bits\":0,"
                     --mode hpc --width 1 --height 1 --samples 32 --reference --json --out ${hostile_out}/hpc_1x1.png)
soft_shadows_hostile(soft_tiny_radius egl 0 "\"exact_by_brute\":true.*\"mismatched_bits\":0,.*every light sample is tested"
                     ${soft_small} --light-radius 1e-6 --reference --json --out ${hostile_out}/soft_tiny_radius.png)
soft_shadows_hostile(soft_far_light egl 0 "\"mean_visible_fraction\":0\\.[0-9]+,.*\"mismatched_bits\":0,"
                     --mode soft ${small} --samples 32 --lut-res 16 --grid 16 --light-pos 1e6,1e6,1e6 --light-radius 1e4
                     --reference --json --out ${hostile_out}/soft_far_light.png)
soft_shadows_hostile(hard_far_light egl 0 "\"shadowed\":[1-9][0-9]*,.*\"reference\":\\{\"samples\":[0-9]+,\"mismatched\":0"
                     --mode hard ${small} --light-pos 1e5,1e5,1e5 --reference --json --out ${hostile_out}/hard_far_light.png)
soft_shadows_hostile(hard_farther_light egl 0 "\"shadowed\":[1-9][0-9]*,.*\"reference\":\\{\"samples\":[0-9]+,\"mismatched\":0"
                     --mode hard ${small} --light-pos 3e8,1e9,-2e8 --reference --json --out ${hostile_out}/hard_farther_light.png)
soft_shadows_hostile(hard_light_past_1e18 egl fail "--light-pos .*cannot light the view samples from there: .*beyond the limit of 1e18"
                     --mode hard ${small} --light-pos 1e20,1e20,1e20 --out ${x})
soft_shadows_hostile(reference_far_light cpu 0 "\"mean_visible_fraction\":0\\.[0-9]+,"
                     ${small} --samples 8 --light-pos 1e10,1e10,1e10 --light-radius 1e8 --json --out ${hostile_out}/reference_far_light.png)
soft_shadows_hostile(width_plus_sign cpu 0 "\"width\":32,\"height\":24"
                     --width +32 --height 24 --samples 4 --json --out ${hostile_out}/width_plus_sign.png)
soft_shadows_hostile(light_pos_spaces cpu 0 "\"position\":\\[-1.2,2.5,0.9\\]"
                     ${small} --samples 4 "--light-pos= -1.2, 2.5 ,0.9" --json --out ${hostile_out}/light_pos_spaces.png)

# ---- every mode at a small size (what the ASan+UBSan build runs the demo on) ----
soft_shadows_hostile(mode_dsm_cpu cpu 0 "\"mode\":\"dsm\".*\"rmse\":0\\.[0-9]+"
                     --mode dsm --dsm-build cpu --scene builtin:grass ${small} --dsm-res 32 --reference --json --out ${hostile_out}/mode_dsm.png)
soft_shadows_hostile(mode_volumetric egl 0 "\"mode\":\"volumetric\".*\"rmse\":[0-9.e-]+"
                     --mode volumetric --scene builtin:columns ${small} --sm-res 64 --reference --json --out ${hostile_out}/mode_volumetric.png)
soft_shadows_hostile(mode_hard_aa egl 0 "\"missed_edge_pixels\":0,"
                     --mode hard --aa edge ${small} --reference --json --out ${hostile_out}/mode_hard_aa.png)
soft_shadows_hostile(mode_hard_check_skips egl 0 "\"identical\":true.*\"mismatched\":0"
                     --mode hard ${small} --check-skips --reference --json --out ${hostile_out}/mode_hard_check_skips.png)
soft_shadows_hostile(mode_soft_frames egl 0 "\"temporal\":\\{\"frames\":2,"
                     ${soft_small} --frames 2 --frames-reference 64 --json --out ${hostile_out}/mode_soft_frames.png)
soft_shadows_hostile(mode_soft_brute_check_skips egl 0 "\"identical\":true.*\"mismatched_bits\":0,"
                     ${soft_small} --lut brute --check-skips --reference --json --out ${hostile_out}/mode_soft_brute.png)
soft_shadows_hostile(mode_hpc_hairball cpu 0 "\"mismatched_bits\":0,"
                     --mode hpc --scene builtin:hairball ${small} --samples 32 --reference --json --out ${hostile_out}/mode_hpc.png)

# ---- the checks can fail: a forced difference exits 1 ----
soft_shadows_hostile(fault_check_skips egl 1 "--check-skips failed: 1 shadow words of --mode soft differ"
                     ${soft_small} --check-skips --out ${hostile_out}/fault_check_skips.png)
soft_shadows_hostile(fault_reference_exact egl 1 "--reference failed: [0-9]+ shadow bits of --mode soft differ from the oracle"
                     ${soft_small} --reference --out ${hostile_out}/fault_reference_exact.png)
soft_shadows_hostile(fault_reference_lut egl 0 "reference: [0-9]+ mismatched bits"
                     ${soft_small} --lut lut --reference --out ${hostile_out}/fault_reference_lut.png)
set_tests_properties(soft_shadows.hostile.fault_check_skips PROPERTIES ENVIRONMENT "PENUMBRA_GL=egl;PENUMBRA_DEMO_FAULT=skips")
set_tests_properties(soft_shadows.hostile.fault_reference_exact soft_shadows.hostile.fault_reference_lut
                     PROPERTIES ENVIRONMENT "PENUMBRA_GL=egl;PENUMBRA_DEMO_FAULT=reference")

# ---- OBJ files: refused naming the file and line, or loaded and rendered ----
set(tri "v 0 0 0\nv 1 0 0\nv 0 1 0\n")
set(tet "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
# name|expect|regex|text
set(obj_cases
    "empty|fail|no triangles \\(0 vertices|"
    "vertices_only|fail|no triangles \\(3 vertices|${tri}"
    "index_past_end|fail|line 4: face uses vertex 9 but the file has 3 vertices|${tri}f 1 2 9\n"
    "index_zero|fail|line 4: face corner '0': vertex index 0 \\(OBJ indices start at 1\\)|${tri}f 0 1 2\n"
    "index_relative_past|fail|line 4: face corner '-5': relative vertex index -5 reaches before the first|${tri}f -5 -2 -1\n"
    "index_overflow|fail|line 4: .*overflows int|${tri}f 1 2 99999999999\n"
    "index_text|fail|line 4: face corner 'a': 'a' is not a vertex index|${tri}f 1 2 a\n"
    "vertex_nan|fail|line 2: vertex 2 has a NaN or infinite coordinate 'nan'|v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"
    "vertex_inf|fail|line 3: vertex 3 has a NaN or infinite coordinate '-inf'|v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n"
    "vertex_past_float|fail|line 2: vertex 2: '1e39' is beyond float range|v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"
    "vertex_hex|fail|line 1: vertex 1: '0x1p3' is not a number|v 0x1p3 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    "vertex_two_coordinates|fail|line 1: 'v' \\(vertex 1\\) needs 3 coordinates, found 2|v 1 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    "vertex_word|fail|line 3: vertex 3: 'zero' is not a number|v 0 0 0\nv 1 0 0\nv zero 1 0\nf 1 2 3\n"
    "texture_missing|fail|line 4: face uses texture coordinate 1 but the file has 0 texture coordinates|${tri}f 1/1/1 2/2/2 3/3/3\n"
    "normal_missing|fail|line 5: face uses normal 2 but the file has 1 normals|${tri}vn 0 0 1\nf 1//1 2//1 3//2\n"
    "coincident|fail|all 3 used vertices coincide|v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n"
    "collinear|fail|every one of the 1 triangles has zero area|v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n"
    "repeated_index_only|fail|no triangles|${tri}f 1 1 2\n"
    "short_faces_only|fail|no triangles|${tri}f 1 2\n"
    "binary_zeros|fail|no triangles|\\0\\0\\0\\0"
    "tetrahedron|0|\"triangles\":6,.*\"mean_visible_fraction\":[01]\\.[0-9]+,|${tet}"
    "crlf|0|\"triangles\":6,|v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nv 0 0 1\r\nf 1 3 2\r\nf 1 2 4\r\nf 1 4 3\r\nf 2 3 4\r\n"
    "quad|0|\"triangles\":4,|v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
    "relative_indices|0|\"triangles\":3,|${tri}f -3 -2 -1\n"
    "faces_before_vertices|0|\"triangles\":3,|f 1 2 3\n${tri}"
    "comment_and_garbage_line|0|\"triangles\":3,|# a comment\nhello world\n${tri}f 1 2 3\n"
    "missing_material|0|\"triangles\":3,|mtllib nothere.mtl\nusemtl x\n${tri}f 1 2 3\n"
    "vertex_colours|0|\"triangles\":3,|v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"
    "short_face_warned|0|\"triangles\":6,.*1 faces of fewer than 3 corners dropped|${tet}f 1 2\n"
    "tiny_coordinates|0|\"triangles\":6,.*\"mean_visible_fraction\":[01]\\.[0-9]+,|v 0 0 0\nv 1e-300 0 0\nv 0 1e-300 0\nv 0 0 1e-300\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    "far_tetrahedron_1e6|0|\"triangles\":6,.*\"mean_visible_fraction\":[01]\\.[0-9]+,|v 1000000.3 0 0\nv 1000001.3 0 0\nv 1000000.3 1 0\nv 1000000.3 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    "far_cube_1e8|0|\"triangles\":14,.*\"mean_visible_fraction\":0\\.[0-9]+,|v 1e8 1e8 1e8\nv 100000001 1e8 1e8\nv 100000001 100000001 1e8\nv 1e8 100000001 1e8\nv 1e8 1e8 100000001\nv 100000001 1e8 100000001\nv 100000001 100000001 100000001\nv 1e8 100000001 100000001\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n")
foreach(case IN LISTS obj_cases)
    string(FIND "${case}" "|" a)
    string(SUBSTRING "${case}" 0 ${a} name)
    math(EXPR a "${a} + 1")
    string(SUBSTRING "${case}" ${a} -1 rest)
    string(FIND "${rest}" "|" b)
    string(SUBSTRING "${rest}" 0 ${b} expect)
    math(EXPR b "${b} + 1")
    string(SUBSTRING "${rest}" ${b} -1 rest)
    string(FIND "${rest}" "|" c)
    string(SUBSTRING "${rest}" 0 ${c} regex)
    math(EXPR c "${c} + 1")
    string(SUBSTRING "${rest}" ${c} -1 text)
    file(WRITE "${hostile_objs}/${name}.obj" "${text}")
    if(expect STREQUAL "fail")
        soft_shadows_hostile(obj_${name} cpu fail "--scene '.*${name}.obj' cannot be loaded: .*${regex}"
                             --scene ${hostile_objs}/${name}.obj --out ${x})
    else()
        soft_shadows_hostile(obj_${name} cpu 0 "${regex}" --scene ${hostile_objs}/${name}.obj ${small} --samples 8 --json
                             --out ${hostile_out}/obj_${name}.png)
    endif()
endforeach()
# 10^5 copies of one triangle: loaded as one, with a warning (was minutes of work, silently).
string(REPEAT "f 1 2 3\n" 100000 copies)
file(WRITE "${hostile_objs}/copies.obj" "${tri}${copies}")
soft_shadows_hostile(obj_copies cpu 0 "\"triangles\":3,.*99999 duplicate triangles removed"
                     --scene ${hostile_objs}/copies.obj ${small} --samples 8 --json --out ${hostile_out}/obj_copies.png)
# A 2 MB comment line.
string(REPEAT "x" 2000000 long_line)
file(WRITE "${hostile_objs}/long_line.obj" "# ${long_line}\n${tri}f 1 2 3\n")
soft_shadows_hostile(obj_long_line cpu 0 "\"triangles\":3,"
                     --scene ${hostile_objs}/long_line.obj ${small} --samples 8 --json --out ${hostile_out}/obj_long_line.png)
