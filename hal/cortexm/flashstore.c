/* The board's configuration store (flashstore.h). */
#include "flashstore.h"

#include <stddef.h>

/* cortex-m4.ld / cortex-m0.ld: the STORE region, FLASHSTORE_PAGES pages. */
extern uint8_t __store_start[];

/* ---- The part: the only code a port replaces ------------------------------
 *
 * QEMU's board has RAM where the part has flash, and its RAM powers on
 * zeroed where a part's flash leaves the factory erased: the emulation
 * keeps every byte inverted, so that a fresh board reads an erased store.
 * On a part: part_read reads the memory-mapped flash as it is, part_erase
 * and part_program unlock the flash controller, start the page erase or
 * the double-word program, wait for it and return false on its error flags
 * (the rules checked above them stay). */
static uint8_t part_read(uint32_t off)
{
	return (uint8_t)~__store_start[off];
}

static bool part_erase(uint32_t page, uint32_t bytes)
{
	volatile uint8_t *p = __store_start + page * FLASHSTORE_PAGE;
	for (uint32_t i = 0; i < bytes; i++)
		p[i] = 0; /* reads 0xFF */
	return true;
}

/* Clears the bits of the word at off that are 0 in w (a flash cell only
 * goes 1 -> 0). */
static bool part_program(uint32_t off, const uint8_t *w)
{
	volatile uint8_t *p = __store_start + off;
	for (uint32_t i = 0; i < FLASHSTORE_WORD; i++)
		p[i] = (uint8_t) ~(part_read(off + i) & w[i]);
	return true;
}

/* ---- The rules, as the part enforces them ---------------------------------- */

#ifdef BOARD_STORE_CUT
static volatile uint32_t cut_at, steps;

void flashstore_arm_cut(uint32_t cut)
{
	steps = 0;
	cut_at = cut;
}

/* This step is the one cut: done half by the caller, then the board waits
 * here for the reset, as a part whose power went. */
static bool cut_now(void)
{
	return cut_at != 0 && ++steps == cut_at;
}

static void halt(void)
{
	for (;;)
		;
}
#endif

static bool fl_read(void *ctx, uint32_t off, void *buf, uint32_t n)
{
	(void)ctx;
	if (off > FLASHSTORE_PAGE * FLASHSTORE_PAGES ||
	    n > FLASHSTORE_PAGE * FLASHSTORE_PAGES - off)
		return false;
	for (uint32_t i = 0; i < n; i++)
		((uint8_t *)buf)[i] = part_read(off + i);
	return true;
}

static bool fl_erase(void *ctx, uint32_t page)
{
	(void)ctx;
	if (page >= FLASHSTORE_PAGES)
		return false;
#ifdef BOARD_STORE_CUT
	if (cut_now()) {
		part_erase(page, FLASHSTORE_PAGE / 2u);
		halt();
	}
#endif
	return part_erase(page, FLASHSTORE_PAGE);
}

/* Whole double words, aligned, each still erased: a part refuses to
 * program a word twice (its ECC), and so does this store. */
static bool fl_program(void *ctx, uint32_t off, const void *buf, uint32_t n)
{
	(void)ctx;
	const uint8_t *b = buf;
	if (off % FLASHSTORE_WORD || n % FLASHSTORE_WORD ||
	    off > FLASHSTORE_PAGE * FLASHSTORE_PAGES ||
	    n > FLASHSTORE_PAGE * FLASHSTORE_PAGES - off)
		return false;
	for (uint32_t w = 0; w < n; w += FLASHSTORE_WORD) {
		for (uint32_t i = 0; i < FLASHSTORE_WORD; i++)
			if (part_read(off + w + i) != 0xFFu)
				return false;
#ifdef BOARD_STORE_CUT
		if (cut_now()) {
			uint8_t half[FLASHSTORE_WORD]; /* its odd bits not yet cleared */
			for (uint32_t i = 0; i < FLASHSTORE_WORD; i++)
				half[i] = b[w + i] | 0xAAu;
			part_program(off + w, half);
			halt();
		}
#endif
		if (!part_program(off + w, b + w))
			return false;
	}
	return true;
}

const hal_store_t flashstore = {
    .page_size = FLASHSTORE_PAGE,
    .pages = FLASHSTORE_PAGES,
    .word = FLASHSTORE_WORD,
    .erased_byte = 0xFF,
    .read = fl_read,
    .erase = fl_erase,
    .program = fl_program,
    .ctx = NULL,
};
