# Finds OpenCV's core and imgproc modules only (Debian: libopencv-core-dev,
# libopencv-imgproc-dev; their CMake config ships only with the libopencv-dev meta-package,
# which pulls in every module). Defines OpenCVCore::core and OpenCVCore::imgproc. Not the
# imgcodecs module: it loads about 120 shared libraries at start-up (image files are read with
# libspng, libjpeg and libtiff instead, nodes/io/image_io.h).
find_path(OpenCVCore_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
foreach(module core imgproc)
  find_library(OpenCVCore_${module}_LIBRARY NAMES opencv_${module})
  mark_as_advanced(OpenCVCore_${module}_LIBRARY)
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenCVCore REQUIRED_VARS OpenCVCore_INCLUDE_DIR
  OpenCVCore_core_LIBRARY OpenCVCore_imgproc_LIBRARY)
if(OpenCVCore_FOUND)
  foreach(module core imgproc)
    if(NOT TARGET OpenCVCore::${module})
      add_library(OpenCVCore::${module} UNKNOWN IMPORTED)
      set_target_properties(OpenCVCore::${module} PROPERTIES
        IMPORTED_LOCATION "${OpenCVCore_${module}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OpenCVCore_INCLUDE_DIR}")
    endif()
  endforeach()
endif()
mark_as_advanced(OpenCVCore_INCLUDE_DIR)
