/* Output of the Cortex-M4F probe: ARM semihosting (SYS_WRITE0, via
 * `bkpt 0xab`) and a tiny integer formatter. No newlib stdio. Text is
 * collected in a line buffer and written at each newline. */
#ifndef WC_ARM_IO_H
#define WC_ARM_IO_H

#include <stdint.h>

void wc_arm_puts(const char *text);
void wc_arm_put_u32(uint32_t value);
void wc_arm_put_i32(int32_t value);
/* value / 10^decimals, e.g. (12345, 2) -> "123.45"; value >= 0. */
void wc_arm_put_fixed(uint32_t value, uint32_t decimals);
/* Writes the pending line (wc_arm_puts flushes by itself at '\n'). */
void wc_arm_flush(void);

#endif /* WC_ARM_IO_H */
