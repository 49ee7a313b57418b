#include "wc_tcu_gearbox.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "wc_cal_image_file.h"
#include "wc_tcu_calibrations.h"

static int number(const char *program, const char *name, const char *text, double lo, double hi, double *out)
{
    char *end = NULL;
    const double v = (text != NULL) ? strtod(text, &end) : 0.0;
    if ((text == NULL) || (end == text) || (*end != '\0') || !(v >= lo) || !(v <= hi)) {
        fprintf(stderr, "%s: %s: '%s' is not a number in [%g, %g]\n", program, name, text ? text : "", lo, hi);
        return -1;
    }
    *out = v;
    return 1;
}

int wc_tcu_gearbox_option(const char *program, int argc, char **argv, int *i, wc_tcu_gearbox_options_t *o)
{
    const char *name = argv[*i];
    const char *value = (*i + 1 < argc) ? argv[*i + 1] : NULL;
    int taken = 0;
    if (strcmp(name, "--gearbox") == 0) {
        o->gearbox = value;
        taken = (value != NULL) ? 1 : -1;
    } else if (strcmp(name, "--gearbox-image") == 0) {
        o->gearbox_image = value;
        taken = (value != NULL) ? 1 : -1;
    } else if (strcmp(name, "--element-image") == 0) {
        if ((value == NULL) || (o->element_images >= WC_GEARBOX_ELEMENTS_MAX)) {
            fprintf(stderr, "%s: --element-image: a file, at most %u\n", program, (unsigned)WC_GEARBOX_ELEMENTS_MAX);
            return -1;
        }
        o->element_image[o->element_images++] = value;
        taken = 1;
    } else if (strcmp(name, "--start-gear") == 0) {
        taken = number(program, name, value, 0.0, (double)(WC_GEARBOX_GEARS_MAX - 1u), &o->start_gear);
        if ((taken == 1) && ((o->start_gear - (double)(unsigned)o->start_gear) > 0.0)) {
            fprintf(stderr, "%s: --start-gear: '%s' is not a gear number\n", program, value);
            return -1;
        }
    } else if (strcmp(name, "--holding-margin") == 0) {
        taken = number(program, name, value, 1.0, 5.0, &o->holding_margin);
    } else if (strcmp(name, "--holding-floor") == 0) {
        taken = number(program, name, value, 0.0, 1e4, &o->holding_floor_Nm);
    } else {
        return 0;
    }
    if (taken == -1) {
        if (value == NULL) { fprintf(stderr, "%s: %s needs a value\n", program, name); }
        return -1;
    }
    *i += 1;
    return 1;
}

int wc_tcu_gearbox_config(const char *program, const wc_tcu_gearbox_options_t *o, const wc_calibration_t *cal,
                          float theta_start_degC, wc_loop_config_t *config, wc_transmission_config_t *tx,
                          wc_cal_set_t images[WC_GEARBOX_ELEMENTS_MAX])
{
    if ((o->gearbox == NULL) && (o->gearbox_image == NULL)) {
        if (o->element_images == 0u) { return 0; }
        fprintf(stderr, "%s: --element-image needs --gearbox or --gearbox-image\n", program);
        return 2;
    }
    if ((o->gearbox != NULL) && (o->gearbox_image != NULL)) {
        fprintf(stderr, "%s: --gearbox and --gearbox-image: one gearbox, not both\n", program);
        return 2;
    }
    static wc_gearbox_t from_image;  /* --gearbox-image: the loop keeps a pointer to it for the program's life */
    const char *name = (o->gearbox != NULL) ? o->gearbox : o->gearbox_image;
    const wc_gearbox_t *gearbox = NULL;
    if (o->gearbox != NULL) {
        gearbox = wc_tcu_find_gearbox(o->gearbox);
        if (gearbox == NULL) {
            fprintf(stderr, "%s: --gearbox: '%s' is not compiled in (8hp)\n", program, o->gearbox);
            return 2;
        }
    } else {
        if (wc_gearbox_image_file_load(o->gearbox_image, program, &from_image) != 0) { return 2; }
        gearbox = &from_image;
    }
    if ((config->shift == NULL) || (config->shift->coordinator != 1u)) {
        fprintf(stderr, "%s: the transmission needs a shift calibration with the coordinator (the whole shift's):"
                        " --shift NAME or an image with it\n", program);
        return 2;
    }
    if ((o->element_images != 0u) && (o->element_images != gearbox->element_count)) {
        fprintf(stderr, "%s: the gearbox %s has %u elements: give --element-image for each, or none\n", program,
                name, (unsigned)gearbox->element_count);
        return 2;
    }
    memset(tx, 0, sizeof *tx);
    tx->gearbox = gearbox;
    for (size_t e = 0u; e < gearbox->element_count; ++e) {
        tx->element[e] = cal;
        if (o->element_images == 0u) { continue; }
        if (wc_cal_image_file_load(o->element_image[e], program, "--element-image", &images[e]) != 0) { return 2; }
        tx->element[e] = &images[e].clutch;
    }
    tx->shift = config->shift;
    tx->holding_margin_factor = (float)o->holding_margin;
    tx->holding_floor_Nm = (float)o->holding_floor_Nm;
    static wc_transmission_t check;  /* wc_transmission_init says why it refuses; wc_loop_init only WC_CAL_NULL */
    const wc_transmission_error_t error = wc_transmission_init(&check, tx, (uint32_t)o->start_gear, theta_start_degC);
    if (error != WC_TRANSMISSION_OK) {
        fprintf(stderr, "%s: the gearbox %s refused (wc_transmission_error_t %d: gearbox 2, element 3, shift 4,"
                        " holding 5, start gear 6)\n", program, name, (int)error);
        return 2;
    }
    config->transmission = tx;
    config->transmission_start_gear = (uint32_t)o->start_gear;
    config->shift = NULL;     /* the transmission's own */
    config->offgoing = NULL;  /* an image's whole shift: the elements are the transmission's */
    return 0;
}
