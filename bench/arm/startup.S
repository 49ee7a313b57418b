/* Minimal Cortex-M4F startup of the instruction-count probe (bench/arm).
 * Vector table at 0x0 (initial SP, reset handler, fault handlers), then the
 * reset handler: enable the FPU (CPACR CP10/CP11 full access) before any
 * float instruction can run, copy .data from flash to RAM, zero .bss, call
 * main, and leave QEMU through semihosting SYS_EXIT with main's verdict. */
    .syntax unified
    .cpu cortex-m4
    .fpu fpv4-sp-d16
    .thumb

    .section .vectors, "a", %progbits
    .global wc_arm_vectors
    .type wc_arm_vectors, %object
wc_arm_vectors:
    .word _estack            /* initial SP: top of RAM */
    .word Reset_Handler
    .word Fault_Handler      /* NMI */
    .word Fault_Handler      /* HardFault */
    .word Fault_Handler      /* MemManage */
    .word Fault_Handler      /* BusFault */
    .word Fault_Handler      /* UsageFault */
    .word 0, 0, 0, 0         /* reserved */
    .word Fault_Handler      /* SVCall */
    .word Fault_Handler      /* DebugMonitor */
    .word 0                  /* reserved */
    .word Fault_Handler      /* PendSV */
    .word Fault_Handler      /* SysTick: never enabled (TICKINT = 0) */
    .size wc_arm_vectors, . - wc_arm_vectors

    .text
    .thumb_func
    .global Reset_Handler
    .type Reset_Handler, %function
Reset_Handler:
    /* CPACR (0xE000ED88) bits 20-23: CP10 and CP11 full access. */
    ldr r0, =0xE000ED88
    ldr r1, [r0]
    orr r1, r1, #(0xF << 20)
    str r1, [r0]
    dsb
    isb
    /* .data: copy the initial values from flash. */
    ldr r0, =_sdata
    ldr r1, =_edata
    ldr r2, =_sidata
1:  cmp r0, r1
    bhs 2f
    ldr r3, [r2], #4
    str r3, [r0], #4
    b 1b
    /* .bss: zero. */
2:  ldr r0, =_sbss
    ldr r1, =_ebss
    movs r2, #0
3:  cmp r0, r1
    bhs 4f
    str r2, [r0], #4
    b 3b
4:  bl main
    /* main returns 0 on success: ADP_Stopped_ApplicationExit (QEMU exits 0),
     * else ADP_Stopped_RunTimeErrorUnknown (QEMU exits 1). */
    ldr r1, =0x20026
    cbz r0, 5f
    ldr r1, =0x20023
5:  movs r0, #0x18           /* SYS_EXIT */
    bkpt 0xab
6:  b 6b
    .size Reset_Handler, . - Reset_Handler

    .thumb_func
    .global Fault_Handler
    .type Fault_Handler, %function
Fault_Handler:
    movs r0, #0x04           /* SYS_WRITE0 */
    ldr r1, =fault_message
    bkpt 0xab
    movs r0, #0x18           /* SYS_EXIT, ADP_Stopped_RunTimeErrorUnknown */
    ldr r1, =0x20023
    bkpt 0xab
7:  b 7b
    .size Fault_Handler, . - Fault_Handler

    .section .rodata.fault_message, "a", %progbits
fault_message:
    .asciz "wc_arm_bench: FAIL: fault exception\n"
