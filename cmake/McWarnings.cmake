# Strict warnings for the firmware core: every firmware target calls mc_firmware_target().
set(MC_FW_WARNINGS -Wall -Wextra -Werror -Wdouble-promotion -Wconversion -Wshadow
    -Wstrict-prototypes -Wmissing-prototypes -Wundef -Wfloat-conversion)

function(mc_firmware_target tgt)
  target_compile_options(${tgt} PRIVATE ${MC_FW_WARNINGS})
  if(CMAKE_C_COMPILER_ID STREQUAL "GNU")
    # float literals without f are caught by -Wdouble-promotion; keep single-precision constants.
    target_compile_options(${tgt} PRIVATE -fsingle-precision-constant)
  endif()
endfunction()

set(MC_SIM_WARNINGS -Wall -Wextra -Werror -Wno-deprecated-declarations)
function(mc_sim_target tgt)
  target_compile_options(${tgt} PRIVATE ${MC_SIM_WARNINGS})
endfunction()
