# Run by the SharedDataPresent test: the folder of shared test data (real VMR images and their reference
# corners) must exist. Usage: cmake -DDIR=<folder> -P check_shared_data.cmake
foreach(f data/vmr/reference_corners.csv data/vmr/VMRImage0.jpg)
  if(NOT EXISTS "${DIR}/${f}")
    message(FATAL_ERROR "shared test data missing: '${DIR}/${f}' does not exist. The tests that read the real "
                        "VMR images expect the shared folder beside the source tree (../shared); configure with "
                        "-DHOVS_SHARED_DIR=<folder> to use another place. Those tests are not run.")
  endif()
endforeach()
message(STATUS "shared test data: ${DIR}")
