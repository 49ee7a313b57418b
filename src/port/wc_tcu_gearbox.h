/* The transmission's options of the host programs (wc_tcu, wc_replay; DESIGN 15): --gearbox NAME (a
 * compiled-in gearbox table) or --gearbox-image FILE (a gearbox image, wc_gearbox_image.h), --element-image FILE per element (each its own clutch; without them every
 * element has the program's clutch calibration), --start-gear N, --holding-margin F, --holding-floor NM.
 * Host code: stdio allowed. */
#ifndef WC_TCU_GEARBOX_H
#define WC_TCU_GEARBOX_H

#include <stddef.h>

#include "wetclutch/wc_transmission.h"
#include "wetclutch_can/wc_cal_image.h"
#include "wetclutch_can/wc_loop.h"

typedef struct {
    const char *gearbox;                                   /* --gearbox NAME; NULL: one clutch */
    const char *gearbox_image;                             /* --gearbox-image FILE (instead of --gearbox) */
    const char *element_image[WC_GEARBOX_ELEMENTS_MAX];    /* --element-image FILE, in element order */
    size_t element_images;
    double start_gear;                                     /* --start-gear N (1) */
    double holding_margin;                                 /* --holding-margin F (1.3) */
    double holding_floor_Nm;                               /* --holding-floor NM (30) */
} wc_tcu_gearbox_options_t;

#define WC_TCU_GEARBOX_OPTIONS_DEFAULT { NULL, NULL, { NULL }, 0u, 1.0, 1.3, 30.0 }
#define WC_TCU_GEARBOX_USAGE                                                                                 \
    "  --gearbox NAME (8hp)  the transmission: every element of this compiled-in gearbox (DESIGN 15); needs a\n" \
    "                        shift calibration with the coordinator (--shift NAME or an image with it)\n"       \
    "  --gearbox-image FILE  the same from a gearbox image (`wetclutch gearbox ... --image FILE`), not --gearbox\n" \
    "  --element-image FILE  one per element, in element order: its clutch (an image with shift off)\n"         \
    "  --start-gear N        the gear held at start (1)\n"                                                     \
    "  --holding-margin F    in a gear: the holding need x F (1.3), --holding-floor NM at least (30)\n"

/* Take the transmission's option at argv[*i] (its value at argv[*i + 1]): 1 taken (*i past the value),
 * 0 not one of them, -1 a bad or missing value (one line on stderr). */
int wc_tcu_gearbox_option(const char *program, int argc, char **argv, int *i, wc_tcu_gearbox_options_t *o);

/* With o->gearbox or o->gearbox_image (loaded into this module's one static table, which the loop keeps a
 * pointer to): the loop's transmission in *tx (element images loaded into images[], which the loop
 * keeps pointers into), config->transmission and its start gear set, config->shift and ->offgoing
 * cleared (the transmission has them). cal: every element's clutch without element images.
 * Without either: nothing (element images then refused). Returns 0, or 2 after one line on stderr
 * saying why (wc_transmission_init's reason for a refused configuration). */
int wc_tcu_gearbox_config(const char *program, const wc_tcu_gearbox_options_t *o, const wc_calibration_t *cal,
                          float theta_start_degC, wc_loop_config_t *config, wc_transmission_config_t *tx,
                          wc_cal_set_t images[WC_GEARBOX_ELEMENTS_MAX]);

#endif /* WC_TCU_GEARBOX_H */
