/* GPIO lines through libgpiod 1.6; see gpio.h. */
#include "gpio.h"

#include <errno.h>
#include <gpiod.h>
#include <stdio.h>
#include <string.h>

#define CONSUMER "vehicle-fw"

static struct gpiod_chip *chip_get(lgpio_t *g, const char *name, char *err, size_t errlen)
{
	for (unsigned i = 0; i < g->nchips; i++)
		if (!strcmp(g->chip_name[i], name))
			return g->chip[i];
	if (g->nchips == LGPIO_MAX_CHIPS) {
		snprintf(err, errlen, "gpio: more than %d chips", LGPIO_MAX_CHIPS);
		return NULL;
	}
	struct gpiod_chip *c = gpiod_chip_open_lookup(name);
	if (!c) {
		snprintf(err, errlen, "gpio: %s: %s", name, strerror(errno));
		return NULL;
	}
	g->chip[g->nchips] = c;
	snprintf(g->chip_name[g->nchips], HAL_IO_CHIP_MAX, "%s", name);
	g->nchips++;
	return c;
}

static struct gpiod_line *line_get(lgpio_t *g, const char *chip, uint32_t off, bool out,
				   bool active_low, const char *what, char *err, size_t errlen)
{
	struct gpiod_chip *c = chip_get(g, chip, err, errlen);
	if (!c)
		return NULL;
	struct gpiod_line *l = gpiod_chip_get_line(c, off);
	if (!l) {
		snprintf(err, errlen, "gpio: %s line %u (%s): %s", chip, off, what,
			 strerror(errno));
		return NULL;
	}
	int flags = active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
	/* Outputs start inactive: relay open, servo disabled, outputs off. */
	int r = out ? gpiod_line_request_output_flags(l, CONSUMER, flags, 0)
		    : gpiod_line_request_input_flags(l, CONSUMER, flags);
	if (r != 0) {
		snprintf(err, errlen, "gpio: %s line %u (%s): request failed: %s", chip, off, what,
			 strerror(errno));
		return NULL;
	}
	return l;
}

static bool fn_is_output(unsigned fn)
{
	return fn == BK_LINE_RELAY || fn >= BK_LINE_SERVO0;
}

int lgpio_open(lgpio_t *g, const backend_cfg_t *bk, const hal_io_map_t *io, char *err,
	       size_t errlen)
{
	memset(g, 0, sizeof(*g));
	for (unsigned fn = 0; fn < BK_LINE_COUNT; fn++) {
		const bk_line_t *d = &bk->lines[fn];
		if (!d->used)
			continue;
		g->fn[fn] = line_get(g, d->chip, d->line, fn_is_output(fn), d->active_low,
				     backend_line_name(fn), err, errlen);
		if (!g->fn[fn])
			goto fail;
	}
	for (unsigned i = 0; io && i < io->n; i++) {
		const hal_io_line_t *m = &io->e[i];
		if (!m->mapped)
			continue;
		lgpio_io_t *e = &g->io[g->nio++];
		e->id = m->id;
		e->width = m->width;
		e->out = m->dir == VS_IO_OUT;
		for (unsigned b = 0; b < m->width; b++) {
			char what[32];
			snprintf(what, sizeof(what), "io %u bit %u", m->id, b);
			e->l[b] = line_get(g, m->chip, m->line + b, e->out, m->active_low, what,
					   err, errlen);
			if (!e->l[b])
				goto fail;
		}
	}
	return 0;
fail:
	lgpio_close(g);
	return -1;
}

void lgpio_close(lgpio_t *g)
{
	/* Closing a chip releases its lines; the kernel leaves an output at
	 * its last value, so drive the safety outputs inactive first. */
	for (unsigned fn = 0; fn < BK_LINE_COUNT; fn++)
		if (g->fn[fn] && fn_is_output(fn))
			gpiod_line_set_value(g->fn[fn], 0);
	for (unsigned i = 0; i < g->nchips; i++)
		gpiod_chip_close(g->chip[i]);
	memset(g, 0, sizeof(*g));
}

bool lgpio_has_fn(const lgpio_t *g, unsigned fn)
{
	return fn < BK_LINE_COUNT && g->fn[fn] != NULL;
}

bool lgpio_get_fn(lgpio_t *g, unsigned fn)
{
	if (!lgpio_has_fn(g, fn))
		return false;
	int v = gpiod_line_get_value(g->fn[fn]);
	if (v < 0) {
		g->errors++;
		return false;
	}
	return v != 0;
}

void lgpio_set_fn(lgpio_t *g, unsigned fn, bool on)
{
	if (lgpio_has_fn(g, fn) && gpiod_line_set_value(g->fn[fn], on ? 1 : 0) != 0)
		g->errors++;
}

static lgpio_io_t *io_find(lgpio_t *g, uint32_t id)
{
	for (unsigned i = 0; i < g->nio; i++)
		if (g->io[i].id == id)
			return &g->io[i];
	return NULL;
}

bool lgpio_io_read(lgpio_t *g, uint32_t id, uint32_t *value)
{
	lgpio_io_t *e = io_find(g, id);
	if (!e)
		return false;
	uint32_t v = 0;
	for (unsigned b = 0; b < e->width; b++) {
		int r = gpiod_line_get_value(e->l[b]);
		if (r < 0) {
			g->errors++;
			return false;
		}
		if (r)
			v |= 1u << b;
	}
	*value = v;
	return true;
}

bool lgpio_io_write(lgpio_t *g, uint32_t id, uint32_t value)
{
	lgpio_io_t *e = io_find(g, id);
	if (!e || !e->out)
		return false;
	for (unsigned b = 0; b < e->width; b++)
		if (gpiod_line_set_value(e->l[b], (int)((value >> b) & 1u)) != 0) {
			g->errors++;
			return false;
		}
	return true;
}
