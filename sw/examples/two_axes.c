/* Two axes sampled in the same clock (docs/driver.md): compiled by `make driver`. */
#include "biss_master.h"

#define BISS_BASE 0x43C00000u       /* where the bus top sits in the CPU's address map */
#define CLK_HZ 100000000u           /* the bus top's clock */

int read_two_axes(uint64_t position[2])
{
    const biss_bus_t bus = { BISS_BASE, biss_mmio_read32, biss_mmio_write32, NULL };
    static const char *const encoder[2] = { "resolute_c_26", "resolute_fs_rsh" };
    biss_channel_t axis[2];
    biss_result_t r;
    int i, err;

    for (i = 0; i < 2; i++)
        if ((err = biss_channel_init(&axis[i], &bus, (unsigned)i)) != BISS_OK ||
            (err = biss_configure_preset(&axis[i], encoder[i], CLK_HZ, 5000000u)) != BISS_OK ||
            (err = biss_set_trigger_enable(&axis[i], true)) != BISS_OK)
            return err;
    biss_trigger(&bus);                 /* both axes start in the same clock */
    for (i = 0; i < 2; i++) {
        if ((err = biss_wait_done(&axis[i], 100000u)) != BISS_OK)
            return err;
        biss_read_result(&axis[i], &r);  /* status first: one frame, never torn */
        if (r.status != BISS_STATUS_OK)
            return -100 - r.status;
        position[i] = r.word0;
    }
    return BISS_OK;
}
