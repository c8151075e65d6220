# Finds OpenCV's core, imgproc and imgcodecs modules only (Debian: libopencv-core-dev,
# libopencv-imgproc-dev, libopencv-imgcodecs-dev; their CMake config ships only with the
# libopencv-dev meta-package, which pulls in every module). Defines OpenCVCore::core,
# OpenCVCore::imgproc and OpenCVCore::imgcodecs.
find_path(OpenCVCore_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
foreach(module core imgproc imgcodecs)
  find_library(OpenCVCore_${module}_LIBRARY NAMES opencv_${module})
  mark_as_advanced(OpenCVCore_${module}_LIBRARY)
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenCVCore REQUIRED_VARS OpenCVCore_INCLUDE_DIR
  OpenCVCore_core_LIBRARY OpenCVCore_imgproc_LIBRARY OpenCVCore_imgcodecs_LIBRARY)
if(OpenCVCore_FOUND)
  foreach(module core imgproc imgcodecs)
    if(NOT TARGET OpenCVCore::${module})
      add_library(OpenCVCore::${module} UNKNOWN IMPORTED)
      set_target_properties(OpenCVCore::${module} PROPERTIES
        IMPORTED_LOCATION "${OpenCVCore_${module}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OpenCVCore_INCLUDE_DIR}")
    endif()
  endforeach()
endif()
mark_as_advanced(OpenCVCore_INCLUDE_DIR)
