# Finds libspng (Debian: libspng-dev), the PNG decoder and encoder behind nodes/io/image_io.
# Defines Spng::spng.
find_path(Spng_INCLUDE_DIR spng.h)
find_library(Spng_LIBRARY NAMES spng)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(Spng REQUIRED_VARS Spng_INCLUDE_DIR Spng_LIBRARY)
if(Spng_FOUND AND NOT TARGET Spng::spng)
  add_library(Spng::spng UNKNOWN IMPORTED)
  set_target_properties(Spng::spng PROPERTIES IMPORTED_LOCATION "${Spng_LIBRARY}"
                        INTERFACE_INCLUDE_DIRECTORIES "${Spng_INCLUDE_DIR}")
endif()
mark_as_advanced(Spng_INCLUDE_DIR Spng_LIBRARY)
