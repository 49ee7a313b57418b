/* Umbrella header of the wet-clutch TCU library (Shin & Choi friction model). */
#ifndef WETCLUTCH_H
#define WETCLUTCH_H

#include "wc_config.h"
#include "wc_status.h"
#include "wc_calibration.h"
#include "wc_model.h"
#include "wc_viscosity.h"
#include "wc_friction.h"
#include "wc_film.h"
#include "wc_torque.h"
#include "wc_thermal.h"
#include "wc_hydraulics.h"
#include "wc_inverse.h"
#include "wc_lockup.h"
#include "wc_clutch.h"
#include "wc_shift.h"
#include "wc_gearbox.h"
#include "wc_adapt.h"
#include "wc_image.h"
#include "wc_adapt_image.h"

/* rpm <-> rad/s, for callers whose sensors speak rpm. */
#define WC_RAD_S_PER_RPM 0.10471975511965977f

#endif /* WETCLUTCH_H */
