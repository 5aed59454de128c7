# The firmware images, cross-built inside the host build so that the processor-in-the-loop tests
# find them: arm-cm4f (generic port, Cortex-M4F) and am263x (TI AM263x, Cortex-R5F), each a
# separate CMake build of this source tree with its toolchain file (the same as the presets).
include(ExternalProject)
find_program(MC_ARM_GCC arm-none-eabi-gcc)
set(MC_IMAGE_DIR ${CMAKE_BINARY_DIR}/images)
set(MC_IMAGES "")
if(NOT MC_ARM_GCC)
  message(STATUS "arm-none-eabi-gcc not found: no firmware images, no PIL tests")
  return()
endif()
foreach(img arm-cm4f am263x)
  if(img STREQUAL "am263x")
    set(tc ${PROJECT_SOURCE_DIR}/cmake/am263x.cmake)
    set(port am263x)
  else()
    set(tc ${PROJECT_SOURCE_DIR}/cmake/arm-none-eabi.cmake)
    set(port generic)
  endif()
  if(NOT EXISTS ${PROJECT_SOURCE_DIR}/hal/${port}/CMakeLists.txt)
    continue()
  endif()
  ExternalProject_Add(image_${img}
    SOURCE_DIR ${PROJECT_SOURCE_DIR}
    BINARY_DIR ${MC_IMAGE_DIR}/${img}
    CMAKE_ARGS -DCMAKE_TOOLCHAIN_FILE=${tc} -DCMAKE_BUILD_TYPE=MinSizeRel -DMC_BUILD_SIM=OFF -DMC_BUILD_TESTS=OFF
    CMAKE_GENERATOR ${CMAKE_GENERATOR}
    BUILD_ALWAYS ON
    INSTALL_COMMAND ""
    USES_TERMINAL_BUILD ON)
  set(MC_IMAGE_${img} ${MC_IMAGE_DIR}/${img}/firmware/image/mc_image_${port}.elf)
  if(img STREQUAL "am263x")   # and its boot image for TI's SBL (firmware/image/CMakeLists.txt)
    set(MC_BOOTIMAGE_${img} ${MC_IMAGE_DIR}/${img}/firmware/image/mc_image_${port}.appimage)
  endif()
  list(APPEND MC_IMAGES ${img})
endforeach()
