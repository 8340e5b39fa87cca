/* sw/examples/bp3_identify.c: the BP3 example of docs/driver.md, compiled by the build. */
#include "biss_master.h"

#define CLK_HZ 100000000u           /* the bus top's clock */

/* A BP3 encoder (slave 0) on channel ch at 10 MHz MA: identify it, read its EDS, set the data
 * channel from the EDS. Before: the data channel set for a frame at least as long as the
 * encoder's (docs/control.md, The data channel before identification). */
int bp3_setup(biss_channel_t *ch, biss_bp3_eds_t *eds)
{
    biss_config_t cfg;
    biss_bp3_id_t id;
    int err;

    if ((err = biss_bp3_identify(ch, 0, &id)) != BISS_OK ||
        (err = biss_bp3_read_eds(ch, 0, 1, eds)) != BISS_OK ||  /* 1: a common EDS bank first */
        (err = biss_config_from_preset(&cfg, "resolute_c_26", CLK_HZ, 10000000u)) != BISS_OK ||
        (err = biss_bp3_config(eds, &cfg)) != BISS_OK ||         /* word 0 from the EDS */
        (err = biss_configure(ch, &cfg)) != BISS_OK)
        return err;
    /* Now id.position_bits == cfg.word[0].data_bits; eds->mt_cnt, eds->sip_res: the scaling. */
    return BISS_OK;
}
