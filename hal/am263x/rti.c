/* Microsecond time base of the AM263x port: RTI0 counter block 0 (am263x/regs_rti.h; TRM: RTI
 * Counter Operation). RTICLK is assumed to be the 25 MHz crystal (AM263X_RTI_CLK_HZ). */
#include "am263x/mmio.h"
#include "am263x/port.h"
#include "am263x/regs_rti.h"

void am263x_time_init(hal_time_t *t, uint32_t rti_clk_hz)
{
    const uintptr_t b = t->rti;
    am263x_wr32(b + RTI_RTIGCTRL, 0u);          /* counters stopped                      */
    am263x_wr32(b + RTI_RTITBCTRL, 0u);         /* counter 0 from RTICLK                 */
    am263x_wr32(b + RTI_RTICAPCTRL, 0u);
    am263x_wr32(b + RTI_RTICOMPCTRL, 0u);
    am263x_wr32(b + RTI_RTIUC0, 0u);
    am263x_wr32(b + RTI_RTIFRC0, 0u);
    am263x_wr32(b + RTI_RTICPUC0, rti_clk_hz / 1000000u - 1u);   /* FRC0 at 1 MHz         */
    am263x_wr32(b + RTI_RTIGCTRL, RTI_GCTRL_CNT0EN);
}

/* ---- hal/time.h */
uint32_t hal_time_us(const hal_time_t *t)
{
    return am263x_rd32(t->rti + RTI_RTIFRC0);
}

void am263x_wdt_start(uintptr_t wdt, uint32_t prld)
{
    am263x_wr32(wdt + RTI_RTIWDSTATUS, 0xFFu);
    am263x_wr32(wdt + RTI_RTIWWDSIZECTRL, RTI_WWDSIZE_100);
    am263x_wr32(wdt + RTI_RTIDWDPRLD, prld);
    am263x_wr32(wdt + RTI_RTIWWDRXNCTRL, RTI_WWDRXN_RESET);
    am263x_wr32(wdt + RTI_RTIDWDCTRL, RTI_DWDCTRL_ENABLE);
}

void am263x_wdt_kick(uintptr_t wdt)
{
    am263x_wr32(wdt + RTI_RTIWDKEY, RTI_WDKEY_1);
    am263x_wr32(wdt + RTI_RTIWDKEY, RTI_WDKEY_2);
}

void hal_wdg_service(hal_wdg_t *wdg)
{
    const uint32_t n = wdg->isr_runs;
    if (n != wdg->seen) {
        wdg->seen = n;
        am263x_wdt_kick(wdg->wdt);
    }
}
