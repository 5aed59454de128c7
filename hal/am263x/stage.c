/* Stage marker (hal/stage.h) and the port's name for the processor-in-the-loop: one store to a
 * RAM variable the PIL watches; the symbol hal_port_name picks sim/pil/dev_am263x.cpp. */
#include "hal/stage.h"

/* kept by the linker script (KEEP(*(.rodata.hal_port_name))): nothing in the image reads it */
__attribute__((used, section(".rodata.hal_port_name"))) const char hal_port_name[] = "am263x";
/* kept by the linker script as well (KEEP(*(.bss.hal_stage_reg))): the PIL looks it up */
__attribute__((used, section(".bss.hal_stage_reg"))) volatile uint32_t hal_stage_reg;

void hal_stage_mark(hal_stage_t stage)
{
    hal_stage_reg = (uint32_t)stage;
}
