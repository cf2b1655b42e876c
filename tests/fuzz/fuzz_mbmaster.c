/* Fuzz target: the board's Modbus RTU master (hal/modbus/mbmaster.c), its
 * reply parser fed whatever a bus may carry, through the drive bus's cycle.
 *
 * Input: chunks, each a control byte (bits 0-4: chunk length, bits 5-7:
 * time before it arrives, 0.2, 0.5, 1, 2, 5, 20, 60 ms or none) and its
 * bytes, delivered to the master as the drives' answers of a two-drive bus
 * (the generic profile with its comm_timeout register, the zlac8015d one
 * when the first byte is odd). Checked: the master only ever sends whole,
 * well-formed requests (its own CRC good, a function it uses), the bytes
 * it reads never exceed its buffer, a sample reaches the tick only after a
 * reply that checks, and the counters add up.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../../hal/modbus/mbmaster.h"

static const uint8_t *in;
static size_t in_n;

static size_t f_read(void *ctx, uint8_t *buf, size_t max)
{
	(void)ctx;
	size_t n = in_n < max ? in_n : max;
	memcpy(buf, in, n);
	in += n;
	in_n -= n;
	return n;
}

static void f_write(void *ctx, const uint8_t *buf, size_t n)
{
	(void)ctx;
	if (n < 8 || n > MBM_ADU_MAX)
		abort();
	uint16_t c = mbm_crc(buf, n - 2);
	if (buf[n - 2] != (c & 0xFF) || buf[n - 1] != (c >> 8))
		abort();
	if (buf[1] != 3 && buf[1] != 4 && buf[1] != 6 && buf[1] != 16)
		abort();
}

static bool f_tx_done(void *ctx)
{
	(void)ctx;
	return true;
}

static void f_de(void *ctx, bool on)
{
	(void)ctx, (void)on;
}

static const mbm_port_t port = {f_read, f_write, f_tx_done, f_de, NULL};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const uint32_t gap_us[8] = {200, 500, 1000, 2000, 5000, 20000, 60000, 0};
	static mbd_bus_t b;
	if (size == 0)
		return 0;
	mb_profile_t p = *mbp_builtin_at(data[0] & 1u);
	p.reg[MBP_COMM_TIMEOUT] = (mbp_reg_t){0x109, 0, 1, 0};
	mbd_init(&b, &p, &port, 115200, 10, 50000, 1, 0);
	b.comm_timeout_ms = 100;
	mbd_add(&b, 1, 0, false);
	mbd_add(&b, p.channels > 1 ? 1 : 2, p.channels > 1 ? 1 : 0, true);
	mbd_enable(&b, 0, true);
	mbd_set_velocity(&b, 1, -1000 * 256);
	uint32_t t = 0;
	size_t i = 1;
	while (i < size) {
		size_t n = data[i] & 0x1Fu;
		uint32_t dt = gap_us[data[i] >> 5];
		i++;
		if (n > size - i)
			n = size - i;
		in = data + i;
		in_n = n;
		i += n;
		/* the bytes arrive within dt; the master polls every 100 us */
		for (uint32_t k = 0; k <= dt; k += 100)
			mbd_poll(&b, t += 100);
		for (unsigned d = 0; d < b.nd; d++) {
			hal_drive_state_t st;
			bool had = b.d[d].s.fresh;
			mbd_read(&b, d, &st);
			if (st.fresh != had || (st.fresh && !b.d[d].s.sampled))
				abort();
		}
	}
	const mbm_count_t *c = &b.m.cnt;
	if (c->retries > c->requests || c->busy + c->illegal > c->exceptions)
		abort();
	return 0;
}
