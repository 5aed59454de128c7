# Print section sizes of the cross-built firmware libraries after they are built.
function(mc_print_sizes)
  find_program(MC_SIZE_TOOL NAMES ${CMAKE_SIZE} arm-none-eabi-size size)
  foreach(lib ${ARGN})
    if(NOT TARGET ${lib})
      continue()
    endif()
    add_custom_command(TARGET ${lib} POST_BUILD
      COMMAND ${CMAKE_COMMAND} -E echo "-- section sizes of lib${lib}.a (text = flash code, data+bss = RAM):"
      COMMAND ${MC_SIZE_TOOL} -t $<TARGET_FILE:${lib}>
      VERBATIM)
  endforeach()
endfunction()
