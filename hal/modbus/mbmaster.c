/* Modbus RTU master for a microcontroller; see mbmaster.h. */
#include "mbmaster.h"

enum { ST_IDLE, ST_GAP, ST_TX, ST_WAIT };

/* The bus's profile: on a board that compiles it in (MBD_PROFILE,
 * mbmaster.h), its reads are constants the compiler folds. */
#ifdef MBD_PROFILE
#define BUS_PROF(b) (&MBD_PROFILE)
#define PROF_INLINE inline __attribute__((always_inline))
#else
#define BUS_PROF(b) ((b)->prof)
#define PROF_INLINE
#endif

/* The port's calls: a board's own functions (MBM_PORT_DIRECT), else
 * through the port. */
#ifdef MBM_PORT_DIRECT
#define PORT_READ(m, buf, max) mbm_port_read(buf, max)
#define PORT_WRITE(m, buf, n)  mbm_port_write(buf, n)
#define PORT_TX_DONE(m)	       mbm_port_tx_done()
#define PORT_DE(m, on)	       mbm_port_de(on)
#else
#define PORT_READ(m, buf, max) ((m)->port->read((m)->port->ctx, buf, max))
#define PORT_WRITE(m, buf, n)  ((m)->port->write((m)->port->ctx, buf, n))
#define PORT_TX_DONE(m)	       ((m)->port->tx_done((m)->port->ctx))
#define PORT_DE(m, on)	       ((m)->port->de((m)->port->ctx, on))
#endif

uint32_t mbm_char_us(uint32_t baud, uint32_t frame_bits)
{
	return (frame_bits * 1000000u + baud - 1u) / baud;
}

uint16_t mbm_crc(const uint8_t *b, size_t n)
{
	uint16_t crc = 0xFFFFu;
	for (size_t i = 0; i < n; i++) {
		crc ^= b[i];
		for (unsigned k = 0; k < 8; k++)
			crc = (crc & 1u) ? (uint16_t)((crc >> 1) ^ 0xA001u) : (uint16_t)(crc >> 1);
	}
	return crc;
}

uint32_t mbm_byte_us(uint32_t baud, uint32_t frame_bits)
{
	uint32_t us = (uint32_t)(4ull * frame_bits * 1000000u / (baud ? baud : 1));
	/* A host's serial driver and a USB adapter deliver a reply in pieces
	 * some milliseconds apart, and so does an emulated board's UART (a
	 * byte per pass of the emulator's I/O loop): below that a good reply
	 * would be cut. */
	return us < MBM_BYTE_MIN_US ? MBM_BYTE_MIN_US : us;
}

void mbm_init(mbm_t *m, const mbm_port_t *port, uint32_t baud, uint32_t frame_bits,
	      uint32_t timeout_us, uint8_t retries, uint32_t now_us)
{
	*m = (mbm_t){0};
	m->port = port;
	m->gap_us = MBM_GAP_US(baud, frame_bits);
	m->byte_us = mbm_byte_us(baud, frame_bits);
	m->timeout_us = timeout_us;
	m->retries = retries;
	m->t_line = now_us;
}

static size_t put_crc(uint8_t *f, size_t n)
{
	uint16_t c = mbm_crc(f, n);
	f[n] = (uint8_t)(c & 0xFFu);
	f[n + 1] = (uint8_t)(c >> 8);
	return n + 2;
}

/* A request's frame: unit, function, address, then a read's count (03,
 * 04), one register's value (06), or a pair's count, byte count and words
 * (16); its length with the CRC. */
static size_t frame(uint8_t *f, uint8_t unit, uint8_t fc, uint16_t addr, uint8_t n,
		    const uint16_t *w)
{
	uint16_t v = fc == 6 ? w[0] : n;
	size_t k = 6;
	f[0] = unit;
	f[1] = fc;
	f[2] = (uint8_t)(addr >> 8);
	f[3] = (uint8_t)(addr & 0xFFu);
	f[4] = (uint8_t)(v >> 8);
	f[5] = (uint8_t)(v & 0xFFu);
	if (fc == 16) {
		f[k++] = (uint8_t)(2u * n);
		for (unsigned i = 0; i < n; i++) {
			f[k++] = (uint8_t)(w[i] >> 8);
			f[k++] = (uint8_t)(w[i] & 0xFFu);
		}
	}
	return put_crc(f, k);
}

/* A write of n (1 or 2) registers: 06, or 16 for a pair. */
#define WRITE_FC(n) ((uint8_t)((n) == 1 ? 6 : 16))

static bool request(mbm_t *m, uint8_t unit, uint8_t fc, uint16_t addr, uint8_t n, const uint16_t *w)
{
	m->txn = (uint8_t)frame(m->tx, unit, fc, addr, n, w);
	m->attempt = 0;
	m->quiet_us = m->gap_us;
	m->state = ST_GAP;
	return true;
}

bool mbm_read(mbm_t *m, uint8_t unit, bool input, uint16_t addr, uint8_t n)
{
	if (m->state != ST_IDLE || n == 0 || n > MBM_READ_MAX)
		return false;
	return request(m, unit, input ? 4 : 3, addr, n, NULL);
}

bool mbm_write(mbm_t *m, uint8_t unit, uint16_t addr, uint8_t n, const uint16_t *w)
{
	if (m->state != ST_IDLE || n == 0 || n > 2)
		return false;
	return request(m, unit, WRITE_FC(n), addr, n, w);
}

static bool crc_ok(const uint8_t *rx, size_t len)
{
	uint16_t c = mbm_crc(rx, len - 2);
	return rx[len - 2] == (c & 0xFFu) && rx[len - 1] == (c >> 8);
}

uint8_t mbm_check(const uint8_t *tx, const uint8_t *rx, size_t n, uint8_t *exc)
{
	uint8_t fc = tx[1];
	bool read = fc == 3 || fc == 4;
	size_t len = 8; /* 06 and 16 echo the address and the value or count */
	if (n == 0)
		return MBM_MORE;
	if (rx[0] != tx[0])
		return MBM_BAD;
	if (n < 2)
		return MBM_MORE;
	if (rx[1] == (fc | 0x80u)) {
		len = 5;
	} else if (rx[1] != fc) {
		return MBM_BAD;
	} else if (read) {
		if (n < 3)
			return MBM_MORE;
		if (rx[2] != 2u * tx[5] || tx[4] != 0)
			return MBM_BAD;
		len = 5u + rx[2];
	}
	if (n < len)
		return MBM_MORE;
	if (!crc_ok(rx, len))
		return MBM_CRC;
	if (rx[1] != fc) { /* fc | 0x80 */
		*exc = rx[2];
		return MBM_EXCEPTION;
	}
	for (unsigned i = 2; i < 6 && !read; i++)
		if (rx[i] != tx[i])
			return MBM_BAD;
	return MBM_OK;
}

uint16_t mbm_reg(const mbm_t *m, unsigned i)
{
	return (uint16_t)((uint16_t)m->rx[3 + 2 * i] << 8 | m->rx[4 + 2 * i]);
}

/* The attempt ended with r: counted; retried, or the request's result. */
static uint8_t end_attempt(mbm_t *m, uint8_t r)
{
	/* each failure's counter, from MBM_NO_REPLY on */
	static const uint8_t counter[] = {
	    offsetof(mbm_count_t, timeouts), offsetof(mbm_count_t, timeouts),
	    offsetof(mbm_count_t, crc_errors), offsetof(mbm_count_t, bad),
	    offsetof(mbm_count_t, exceptions)};
	_Static_assert(MBM_EXCEPTION - MBM_NO_REPLY == sizeof counter - 1, "a counter a failure");
	mbm_count_t *c = &m->cnt;
	bool illegal = r == MBM_EXCEPTION && (m->exc == 1 || m->exc == 2);
	if (r != MBM_OK)
		(*(uint32_t *)((char *)c + counter[r - MBM_NO_REPLY]))++;
	if (r == MBM_EXCEPTION) {
		c->busy += m->exc == 6;
		c->illegal += illegal;
	}
	if (r == MBM_OK || illegal || m->attempt >= m->retries) {
		m->state = ST_IDLE;
		return r;
	}
	m->attempt++;
	c->retries++;
	/* after the line has been silent for the byte timeout: the rest of a
	 * late or cut answer is read and dropped meanwhile */
	m->quiet_us = m->byte_us;
	m->state = ST_GAP;
	return MBM_BUSY;
}

uint8_t mbm_poll(mbm_t *m, uint32_t now_us)
{
	size_t k;
	switch (m->state) {
	case ST_WAIT:
		k = PORT_READ(m, m->rx + m->rxn, MBM_ADU_MAX - m->rxn);
		if (k) {
			m->rxn = (uint8_t)(m->rxn + k);
			m->t_line = now_us;
			uint8_t r = mbm_check(m->tx, m->rx, m->rxn, &m->exc);
			if (r == MBM_MORE && m->rxn == MBM_ADU_MAX)
				r = MBM_BAD;
			return r == MBM_MORE ? MBM_BUSY : end_attempt(m, r);
		}
		if (now_us - m->t_line >= (m->rxn ? m->byte_us : m->timeout_us))
			return end_attempt(m, m->rxn ? MBM_CUT : MBM_NO_REPLY);
		return MBM_BUSY;
	case ST_TX:
		if (PORT_TX_DONE(m)) {
			PORT_DE(m, false);
			m->t_line = now_us;
			m->rxn = 0;
			m->state = ST_WAIT;
		}
		return MBM_BUSY;
	default:
		/* Idle or before a request: whatever comes is late or stray, and
		 * the line must then be silent for the gap again. */
		if (PORT_READ(m, m->rx, MBM_ADU_MAX))
			m->t_line = now_us;
		else if (m->state == ST_GAP && now_us - m->t_line >= m->quiet_us) {
			PORT_DE(m, true);
			PORT_WRITE(m, m->tx, m->txn);
			m->cnt.requests++;
			m->state = ST_TX;
		}
		return MBM_BUSY;
	}
}

/* ---- the drive bus ------------------------------------------------------ */

enum { DS_NONE, DS_INIT, DS_RESET, DS_ENABLE, DS_SPEED, DS_READ };

/* Characters of a request and its reply, x2. */
static uint32_t req_halfchars(uint32_t req, uint32_t rep)
{
	return 2u * (req + rep);
}

uint32_t mbd_cycle_us(const mb_profile_t *p, unsigned ndrives, uint32_t baud, uint32_t frame_bits,
		      uint32_t turnaround_us)
{
	uint32_t half = 0, nreq = 0;
	uint8_t sw = p->reg[MBP_SPEED].words;
	for (unsigned i = 0; i < ndrives; i++) {
		mbp_read_t rd[3];
		unsigned n = mbp_read_plan(p, i % p->channels, MBM_READ_MAX, rd);
		half += req_halfchars(sw == 1 ? 8u : 9u + 2u * sw, 8u);
		for (unsigned k = 0; k < n; k++)
			half += req_halfchars(8u, 5u + 2u * rd[k].n);
		nreq += 1u + n;
	}
	uint64_t line_us = ((uint64_t)half * frame_bits * 1000000u + (uint64_t)2u * baud - 1u) /
			   ((uint64_t)2u * baud);
	return (uint32_t)line_us + nreq * (turnaround_us + MBM_GAP_US(baud, frame_bits));
}

const char *mbd_check(const mb_profile_t *p, unsigned ndrives, uint32_t baud, uint32_t frame_bits,
		      uint32_t timeout_us, uint8_t retries, uint32_t drive_timeout_ms)
{
	if (ndrives == 0 || ndrives > MBD_DRIVES)
		return "drives: 1 to 4 on a bus";
	if (baud < 1200u || baud > 1000000u)
		return "baud: 1200 to 1000000";
	uint32_t cycle = mbd_cycle_us(p, ndrives, baud, frame_bits, MBD_TURNAROUND_US);
	if (!MBD_LINE_OK(cycle, timeout_us, retries, drive_timeout_ms))
		return "the line does not carry the drive cycle: a cycle and a failed request "
		       "must fit twice in drive_timeout_ms";
	return NULL;
}

void mbd_init(mbd_bus_t *b, const mb_profile_t *p, const mbm_port_t *port, uint32_t baud,
	      uint32_t frame_bits, uint32_t timeout_us, uint8_t retries, uint32_t now_us)
{
	*b = (mbd_bus_t){0};
	mbm_init(&b->m, port, baud, frame_bits, timeout_us, retries, now_us);
#ifdef MBD_PROFILE
	(void)p; /* read as BUS_PROF(b): no reference keeps the object */
#else
	b->prof = p;
#endif
	b->retries = retries;
	b->cur = MBD_DRIVES - 1u;
	b->cycle_start = now_us;
}

unsigned mbd_add(mbd_bus_t *b, uint8_t unit, uint8_t ch, bool reverse)
{
	mbd_drive_t *d = &b->d[b->nd];
	*d = (mbd_drive_t){0};
	d->unit = unit;
	d->ch = ch;
	d->reverse = reverse;
	b->cur = b->nd;
	return b->nd++;
}

static PROF_INLINE bool write_reg(mbd_bus_t *b, const mbd_drive_t *d, unsigned r, int32_t v)
{
	const mbp_reg_t *g = &BUS_PROF(b)->reg[r];
	uint16_t w[2];
	mbp_put(g, v, w);
	return mbm_write(&b->m, d->unit, mbp_addr(g, d->ch), g->words, w);
}

/* A register shared by the unit's channels is on only while every drive of
 * the unit is commanded on. */
static bool enable_wanted(const mbd_bus_t *b, const mbd_drive_t *d)
{
	if (BUS_PROF(b)->reg[MBP_ENABLE].step != 0)
		return d->cmd_enable;
	for (unsigned i = 0; i < b->nd; i++)
		if (b->d[i].unit == d->unit && !b->d[i].cmd_enable)
			return false;
	return true;
}

/* The next request of drive d's cycle; false when the cycle is complete. */
static bool issue(mbd_bus_t *b, mbd_drive_t *d, const mbp_read_t *rd, unsigned nrd)
{
	const mb_profile_t *p = BUS_PROF(b);
	for (;;) {
		switch (b->step) {
		case DS_INIT:
			if (!d->setup_done && b->sub < p->ninit)
				return mbm_write(&b->m, d->unit, p->init[b->sub].addr, 1,
						 &p->init[b->sub].value);
			if (!d->setup_done && b->sub == p->ninit && b->comm_timeout_ms &&
			    p->reg[MBP_COMM_TIMEOUT].words) {
				uint32_t u =
				    (b->comm_timeout_ms + p->comm_unit_ms - 1u) / p->comm_unit_ms;
				return write_reg(b, d, MBP_COMM_TIMEOUT,
						 (int32_t)(u > 65535u ? 65535u : u));
			}
			d->setup_done = true;
			b->step = DS_RESET;
			break;
		case DS_RESET:
			if (d->reset_req != d->reset_done && p->reg[MBP_RESET].words)
				return write_reg(b, d, MBP_RESET, p->reset_value);
			b->step = DS_ENABLE;
			break;
		case DS_ENABLE: {
			bool en = enable_wanted(b, d);
			if (!d->enable_ok || d->enable_sent != en) {
				d->enable_sent = en;
				return write_reg(b, d, MBP_ENABLE,
						 en ? p->enable_on : p->enable_off);
			}
			b->step = DS_SPEED;
			break;
		}
		case DS_SPEED: {
			/* a speed only to a stage that is on: it starts from 0 */
			int32_t cps = d->cmd_enable && mbp_enabled(p, d->s.status) ? d->cmd_cps : 0;
			uint16_t w[2];
			mbp_speed_words(p, cps, w);
			const mbp_reg_t *g = &p->reg[MBP_SPEED];
			return mbm_write(&b->m, d->unit, mbp_addr(g, d->ch), g->words, w);
		}
		default: /* DS_READ */
			if (b->sub < nrd) {
				const mbp_read_t *r = &rd[b->sub];
				return mbm_read(&b->m, d->unit, r->input, r->addr, r->n);
			}
			return false;
		}
	}
}

/* The request of the current step succeeded. */
static void step_done(mbd_bus_t *b, mbd_drive_t *d, const mbp_read_t *rd, unsigned nrd)
{
	switch (b->step) {
	case DS_INIT:
		b->sub++;
		break;
	case DS_RESET:
		d->reset_done = d->reset_req;
		b->step = DS_ENABLE;
		break;
	case DS_ENABLE:
		d->enable_ok = true;
		b->step = DS_SPEED;
		break;
	case DS_SPEED:
		b->step = DS_READ;
		b->sub = 0;
		break;
	default: { /* DS_READ: the read issue() made */
		uint16_t regs[MBM_READ_MAX];
		if (b->sub < nrd) {
			for (unsigned i = 0; i < rd[b->sub].n; i++)
				regs[i] = mbm_reg(&b->m, i);
			mbp_take_read(BUS_PROF(b), d->ch, &rd[b->sub], regs, b->val);
		}
		b->sub++;
		break;
	}
	}
}

/* The request of the current step failed with r: a reset or an enable
 * write that fails leaves the cycle going on (tried again next cycle), any
 * other ends it. */
static bool step_failed(mbd_bus_t *b, mbd_drive_t *d, uint8_t r, uint32_t now_us)
{
	if (b->step == DS_RESET || b->step == DS_ENABLE) {
		b->step++;
		return true;
	}
	uint8_t exc = r == MBM_EXCEPTION ? b->m.exc : 0;
	d->failures++;
	d->s.why = exc == 6		  ? HAL_SILENT_BUSY
		   : exc == 1 || exc == 2 ? HAL_SILENT_MAP
					  : HAL_SILENT_NO_REPLY;
	d->silent = r != MBM_EXCEPTION; /* an exception: it answers */
	if (d->silent) {
		/* nothing usable: probed from now on; it may have restarted */
		d->setup_done = false;
		d->probe_at = now_us + MBD_PROBE_US;
	}
	return false;
}

static void publish(mbd_bus_t *b, mbd_drive_t *d, uint32_t now_us)
{
	mbp_sample_set(BUS_PROF(b), &d->s, b->val);
	d->silent = false;
	d->last_ok_us = now_us;
	d->samples++;
}

/* The next drive whose turn it is (a silent one only when its probe is
 * due); false when none is. */
static bool next_drive(mbd_bus_t *b, uint32_t now_us)
{
	for (unsigned k = 0; k < b->nd; k++) {
		b->cur = (uint8_t)(b->cur + 1u >= b->nd ? 0u : b->cur + 1u);
		if (b->cur == 0) {
			b->cycle_us = now_us - b->cycle_start;
			b->cycle_start = now_us;
			b->cycles++;
			if (b->cycles > 1 && b->cycle_us > b->cycle_worst_us)
				b->cycle_worst_us = b->cycle_us;
		}
		const mbd_drive_t *d = &b->d[b->cur];
		if (!d->silent || (int32_t)(now_us - d->probe_at) >= 0) {
			b->step = DS_INIT;
			b->sub = 0;
			return true;
		}
	}
	return false;
}

void mbd_poll(mbd_bus_t *b, uint32_t now_us)
{
	uint8_t r = mbm_poll(&b->m, now_us);
	if (b->m.state != ST_IDLE || b->nd == 0)
		return;
	mbd_drive_t *d = &b->d[b->cur];
	/* The sample's reads of this drive, planned here once, where a board's
	 * constant profile folds them (MBD_PROFILE): issue() reaches them only
	 * on the drive whose speed write or read step_done() took. */
	mbp_read_t rd[3];
	unsigned nrd = mbp_read_plan(BUS_PROF(b), d->ch, MBM_READ_MAX, rd);
	if (r == MBM_OK)
		step_done(b, d, rd, nrd);
	else if (r != MBM_BUSY && !step_failed(b, d, r, now_us))
		b->step = DS_NONE;
	if (b->step == DS_NONE && !next_drive(b, now_us))
		return;
	d = &b->d[b->cur];
	/* a silent drive gets one attempt a probe */
	b->m.retries = d->silent ? 0 : b->retries;
	if (!issue(b, d, rd, nrd)) {
		publish(b, d, now_us);
		b->step = DS_NONE;
	}
}

void mbd_set_velocity(void *ctx, uint8_t axis, int32_t cps_q8)
{
	mbd_drive_t *d = &((mbd_bus_t *)ctx)->d[axis];
	/* counts/s, rounded to nearest (halves away from zero), on the
	 * magnitude: 32-bit, no 64-bit division */
	uint32_t mag = cps_q8 < 0 ? 0u - (uint32_t)cps_q8 : (uint32_t)cps_q8;
	int32_t cps = (int32_t)((mag + 128u) >> 8);
	d->cmd_cps = (cps_q8 < 0) != d->reverse ? -cps : cps; /* within +-2^23 */
}

void mbd_enable(void *ctx, uint8_t axis, bool on)
{
	mbd_drive_t *d = &((mbd_bus_t *)ctx)->d[axis];
	d->cmd_enable = on;
	if (!on)
		d->cmd_cps = 0;
}

void mbd_reset_fault(void *ctx, uint8_t axis)
{
	((mbd_bus_t *)ctx)->d[axis].reset_req++;
}

void mbd_read(void *ctx, uint8_t axis, hal_drive_state_t *st)
{
	mbd_bus_t *b = ctx;
	mbp_report(BUS_PROF(b), &b->d[axis].s, b->d[axis].reverse, st);
}

size_t mbd_off_frame(const mbd_bus_t *b, unsigned i, uint8_t *f)
{
	const mbp_reg_t *g = &BUS_PROF(b)->reg[MBP_ENABLE];
	uint16_t w[2];
	uint8_t n = g->words == 2 ? 2 : 1; /* mbp_put's words */
	mbp_put(g, BUS_PROF(b)->enable_off, w);
	return frame(f, b->d[i].unit, WRITE_FC(n), mbp_addr(g, b->d[i].ch), n, w);
}
