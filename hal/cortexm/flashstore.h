/* The board's configuration store (hal_store_t, hal/hal.h): two pages of
 * the part's flash at the end of its flash (the linker script's STORE
 * region), with the rules of an STM32L4/G4-class Cortex-M4 part: 2 KiB
 * pages erased whole to 0xFF, 64-bit double words programmed once each
 * after an erase, bits only cleared. On QEMU's mps2-an386 that address is
 * RAM: no load segment of the image covers it, so neither the debugger's
 * load nor QEMU's system reset writes it, and the startup code does not
 * touch it; the bytes survive a reset as a part's flash does. Porting to a
 * real part: docs/mcu.md (the three part_* functions of flashstore.c). */
#ifndef BOARD_FLASHSTORE_H
#define BOARD_FLASHSTORE_H

#include "../hal.h"

#define FLASHSTORE_PAGE	 2048u
#define FLASHSTORE_PAGES 2u
#define FLASHSTORE_WORD	 8u

extern const hal_store_t flashstore;

#ifdef BOARD_STORE_CUT
/* The reset-in-the-save test image only (tests/mcu): after arming, the
 * store's steps (a page erased, a word programmed) are counted from 1; step
 * cut is done half (the page's first half erased, the word's first half
 * programmed) and the board stops there until it is reset. 0: none. */
void flashstore_arm_cut(uint32_t cut);
#endif

#endif
