/* Watchdog: started by hal_board_start with the port's timeout (hal/am263x: RTI DWWD, ~10 ms;
 * hal/generic: GEN_WDT, 10 ms), never stopped. Its expiry turns the outputs off (on the AM263x
 * through a warm reset, see am263x/port.h; the generic part clears PWM CTRL in hardware).
 * Kick it only where the control loop has proven progress: hal_wdg_service, called by the image's
 * background loop and from inside the NVM driver's busy-waits, kicks only when the port's count of
 * control-ISR entries advanced since its last kick. So a stalled ISR and a hung background loop
 * both let it expire, while a flash erase that takes hundreds of ms with the ISR running (a
 * CANopen store) does not; those waits are bounded by their poll counts, so a hung flash still
 * returns to the loop. */
#ifndef HAL_WATCHDOG_H
#define HAL_WATCHDOG_H

typedef struct hal_wdg hal_wdg_t;   /* defined by the port */

/* The count restarted from the timeout. */
void hal_wdg_kick(hal_wdg_t *wdg);

/* hal_wdg_kick if the control ISR ran since the last kick by this call, else nothing. */
void hal_wdg_service(hal_wdg_t *wdg);

#endif
