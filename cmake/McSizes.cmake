# Print section sizes of the cross-built firmware libraries at the end of every build.
function(mc_print_sizes)
  find_program(MC_SIZE_TOOL NAMES ${CMAKE_SIZE} arm-none-eabi-size size REQUIRED)
  set(files "")
  set(deps "")
  foreach(lib ${ARGN})
    if(TARGET ${lib})
      list(APPEND files $<TARGET_FILE:${lib}>)
      list(APPEND deps ${lib})
    endif()
  endforeach()
  add_custom_target(mc_sizes ALL
    COMMAND ${CMAKE_COMMAND} -E echo "-- section sizes (text = flash code, data+bss = RAM):"
    COMMAND ${MC_SIZE_TOOL} -t ${files}
    DEPENDS ${deps}
    VERBATIM)
endfunction()
