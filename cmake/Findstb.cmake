# Findstb — the stb single-file libraries as packaged by Debian/Ubuntu (libstb-dev): headers in
# <prefix>/include/stb/ and libstb, which holds the compiled implementations (stb_image_write
# among them). Defines the imported target stb::stb (include dir + library) and stb_FOUND.
# Used by penumbra's build and installed beside penumbraConfig.cmake, which calls
# find_dependency(stb) for penumbra::support. Hints: stb_INCLUDE_DIR, stb_LIBRARY.
find_path(stb_INCLUDE_DIR stb_image_write.h PATH_SUFFIXES stb)
find_library(stb_LIBRARY stb)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(stb REQUIRED_VARS stb_LIBRARY stb_INCLUDE_DIR)
if(stb_FOUND AND NOT TARGET stb::stb)
    add_library(stb::stb UNKNOWN IMPORTED)
    set_target_properties(stb::stb PROPERTIES IMPORTED_LOCATION "${stb_LIBRARY}"
                                              INTERFACE_INCLUDE_DIRECTORIES "${stb_INCLUDE_DIR}")
endif()
mark_as_advanced(stb_INCLUDE_DIR stb_LIBRARY)
