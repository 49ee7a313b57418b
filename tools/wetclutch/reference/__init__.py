"""The double-precision references the firmware is tested against, independent of its code:

model     the control model (DESIGN 2, 9), one module per concern: film, squeeze film, friction and torque,
          inverse, thermal, lock-up, the clutch step (ClutchReference)
evaluate  ``wetclutch reference``: the model on CSV columns under the firmware's input rules (wc_eval's twin)
shift     the shift controller (src/model/wc_shift.c, DESIGN 10): ShiftReference
adaptation  the adaptation (src/model/wc_adapt.c, DESIGN 12) from wc_adapt.h's specification:
          AdaptationReference (the learned values, the window, the update), the model correction it makes

The bottom of the package with util/: at run time it imports nothing else of wetclutch (its annotations name
calibration.Calibration, whose loader checks the film table with model.film).
"""
