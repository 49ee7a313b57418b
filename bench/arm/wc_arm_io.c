#include "wc_arm_io.h"

#include <stddef.h>

#define SEMIHOSTING_SYS_WRITE0 0x04u
#define LINE_BYTES 160u

static char line[LINE_BYTES + 1u];
static uint32_t line_length;

static void semihosting_write0(const char *text)
{
    register uint32_t r0 __asm__("r0") = SEMIHOSTING_SYS_WRITE0;
    register const char *r1 __asm__("r1") = text;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
}

void wc_arm_flush(void)
{
    if (line_length > 0u) {
        line[line_length] = '\0';
        semihosting_write0(line);
        line_length = 0u;
    }
}

static void put_char(char c)
{
    if (line_length >= LINE_BYTES) { wc_arm_flush(); }
    line[line_length] = c;
    line_length++;
    if (c == '\n') { wc_arm_flush(); }
}

void wc_arm_puts(const char *text)
{
    for (const char *p = text; *p != '\0'; ++p) { put_char(*p); }
}

void wc_arm_put_u32(uint32_t value)
{
    char digits[10];
    uint32_t n = 0u;
    do {
        digits[n] = (char)('0' + (char)(value % 10u));
        value /= 10u;
        n++;
    } while (value != 0u);
    while (n > 0u) {
        n--;
        put_char(digits[n]);
    }
}

void wc_arm_put_i32(int32_t value)
{
    if (value < 0) {
        put_char('-');
        wc_arm_put_u32(0u - (uint32_t)value);
    } else {
        wc_arm_put_u32((uint32_t)value);
    }
}

void wc_arm_put_fixed(uint32_t value, uint32_t decimals)
{
    uint32_t scale = 1u;
    for (uint32_t i = 0u; i < decimals; ++i) { scale *= 10u; }
    wc_arm_put_u32(value / scale);
    if (decimals > 0u) {
        put_char('.');
        uint32_t fraction = value % scale;
        for (uint32_t i = 0u; i < decimals; ++i) {
            scale /= 10u;
            put_char((char)('0' + (char)(fraction / scale)));
            fraction %= scale;
        }
    }
}
