/* An ARM (Cortex-M) image of the generic port without a vector table: code at address 0. The
 * PIL loader must refuse it (tests/pil/test_pil_loader.cpp). */
const char hal_port_name[] = "generic";
void start(void);
void start(void)
{
    for (;;) {
    }
}
