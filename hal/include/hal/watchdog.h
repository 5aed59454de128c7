/* Watchdog: started by hal_board_start with the port's timeout (hal/am263x: RTI DWWD, ~10 ms;
 * hal/generic: GEN_WDT, 10 ms), never stopped. Its expiry turns the outputs off (on the AM263x
 * through a warm reset, see am263x/port.h; the generic part clears PWM CTRL in hardware).
 * Kick it only where the control loop has proven progress: the image's background loop kicks
 * when the control ISR's count advanced since its last kick, so a stalled ISR and a hung
 * background loop both let it expire. */
#ifndef HAL_WATCHDOG_H
#define HAL_WATCHDOG_H

typedef struct hal_wdg hal_wdg_t;   /* defined by the port */

/* The count restarted from the timeout. */
void hal_wdg_kick(hal_wdg_t *wdg);

#endif
