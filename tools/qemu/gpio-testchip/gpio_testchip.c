// SPDX-License-Identifier: GPL-2.0
/*
 * Test GPIO chip for QEMU guest tests: 16 lines that a test drives and
 * observes through module parameters, so userspace GPIO code (libgpiod) can
 * be exercised against a real kernel gpiochip without hardware.
 *
 *   /sys/module/gpio_testchip/parameters/inputs   (rw) level seen on input lines, bit n = line n
 *   /sys/module/gpio_testchip/parameters/outputs  (ro) level driven on output lines
 *   /sys/module/gpio_testchip/parameters/dirs     (ro) direction, bit set = output
 *
 * Reading a line configured as output returns its driven level, as real
 * hardware with output readback does. A write to inputs that changes an input
 * line raises that line's interrupt when its requested edge matches, so edge
 * events (gpiomon, libgpiod event requests) work too.
 */
#include <linux/bitops.h>
#include <linux/gpio/driver.h>
#include <linux/irq.h>
#include <linux/irqdomain.h>
#include <linux/module.h>
#include <linux/spinlock.h>

#define TC_NGPIO 16

static unsigned int inputs;
static int tc_set_inputs(const char *val, const struct kernel_param *kp);
static const struct kernel_param_ops tc_inputs_ops = {
    .set = tc_set_inputs,
    .get = param_get_uint,
};
module_param_cb(inputs, &tc_inputs_ops, &inputs, 0644);
MODULE_PARM_DESC(inputs, "input line levels, bit n = line n");

static unsigned int outputs;
module_param(outputs, uint, 0444);
MODULE_PARM_DESC(outputs, "levels driven on output lines");

static unsigned int dirs;
module_param(dirs, uint, 0444);
MODULE_PARM_DESC(dirs, "line directions, bit set = output");

/* Guards read-modify-write of outputs and dirs; inputs is written whole. */
static DEFINE_SPINLOCK(tc_lock);

static const char *const tc_names[TC_NGPIO] = {
    "tc0", "tc1", "tc2",  "tc3",  "tc4",  "tc5",  "tc6",  "tc7",
    "tc8", "tc9", "tc10", "tc11", "tc12", "tc13", "tc14", "tc15",
};

static void tc_update(unsigned int *word, unsigned int offset, int value)
{
	unsigned long flags;

	spin_lock_irqsave(&tc_lock, flags);
	if (value)
		WRITE_ONCE(*word, *word | BIT(offset));
	else
		WRITE_ONCE(*word, *word & ~BIT(offset));
	spin_unlock_irqrestore(&tc_lock, flags);
}

static int tc_get_direction(struct gpio_chip *gc, unsigned int offset)
{
	return (READ_ONCE(dirs) & BIT(offset)) ? GPIO_LINE_DIRECTION_OUT : GPIO_LINE_DIRECTION_IN;
}

static int tc_direction_input(struct gpio_chip *gc, unsigned int offset)
{
	tc_update(&dirs, offset, 0);
	return 0;
}

static int tc_direction_output(struct gpio_chip *gc, unsigned int offset, int value)
{
	/* Level first, so the line never glitches to a stale value. */
	tc_update(&outputs, offset, value);
	tc_update(&dirs, offset, 1);
	return 0;
}

static int tc_get(struct gpio_chip *gc, unsigned int offset)
{
	unsigned int src = (READ_ONCE(dirs) & BIT(offset)) ? READ_ONCE(outputs) : READ_ONCE(inputs);

	return !!(src & BIT(offset));
}

static void tc_set(struct gpio_chip *gc, unsigned int offset, int value)
{
	tc_update(&outputs, offset, value);
}

/* One interrupt per line; edges are raised in software from tc_set_inputs(). */
static struct irq_domain *tc_domain;

static void tc_irq_nop(struct irq_data *d) {}

static int tc_irq_set_type(struct irq_data *d, unsigned int type)
{
	return (type & ~IRQ_TYPE_EDGE_BOTH) ? -EINVAL : 0;
}

static struct irq_chip tc_irq_chip = {
    .name = "vs-testchip",
    .irq_mask = tc_irq_nop,
    .irq_unmask = tc_irq_nop,
    .irq_set_type = tc_irq_set_type,
};

static int tc_irq_map(struct irq_domain *d, unsigned int virq, irq_hw_number_t hw)
{
	irq_set_chip_and_handler(virq, &tc_irq_chip, handle_simple_irq);
	return 0;
}

static const struct irq_domain_ops tc_irq_ops = {
    .map = tc_irq_map,
};

static int tc_to_irq(struct gpio_chip *gc, unsigned int offset)
{
	return irq_create_mapping(tc_domain, offset);
}

static int tc_set_inputs(const char *val, const struct kernel_param *kp)
{
	unsigned long flags, changed;
	unsigned int old, new, offset;
	int ret;

	ret = kstrtouint(val, 0, &new);
	if (ret)
		return ret;
	spin_lock_irqsave(&tc_lock, flags);
	old = inputs;
	WRITE_ONCE(inputs, new);
	changed = (old ^ new) & ~dirs & GENMASK(TC_NGPIO - 1, 0);
	spin_unlock_irqrestore(&tc_lock, flags);

	/* Before the chip is registered (load-time parameter) nothing listens. */
	if (!tc_domain)
		return 0;
	for_each_set_bit (offset, &changed, TC_NGPIO) {
		unsigned int irq = irq_find_mapping(tc_domain, offset);
		struct irq_data *d = irq ? irq_get_irq_data(irq) : NULL;
		unsigned int type, edge;

		/*
		 * No listener, no event: an edge raised while the interrupt is
		 * freed or disabled would be latched and replayed to the next
		 * requester as a stale event.
		 */
		if (!d || irqd_irq_disabled(d))
			continue;
		type = irqd_get_trigger_type(d);
		edge = (new &BIT(offset)) ? IRQ_TYPE_EDGE_RISING : IRQ_TYPE_EDGE_FALLING;
		if (type & edge)
			generic_handle_irq_safe(irq);
	}
	return 0;
}

static struct gpio_chip tc_chip = {
    .label = "vs-testchip",
    .owner = THIS_MODULE,
    .base = -1,
    .ngpio = TC_NGPIO,
    .names = tc_names,
    .get_direction = tc_get_direction,
    .direction_input = tc_direction_input,
    .direction_output = tc_direction_output,
    .get = tc_get,
    .set = tc_set,
    .to_irq = tc_to_irq,
};

static int __init tc_init(void)
{
	int ret;

	/* All lines start as inputs; parameters given at load time are kept. */
	dirs = 0;
	tc_domain = irq_domain_create_linear(NULL, TC_NGPIO, &tc_irq_ops, NULL);
	if (!tc_domain)
		return -ENOMEM;
	ret = gpiochip_add_data(&tc_chip, NULL);
	if (ret)
		irq_domain_remove(tc_domain);
	return ret;
}

static void __exit tc_exit(void)
{
	unsigned int offset;

	gpiochip_remove(&tc_chip);
	for (offset = 0; offset < TC_NGPIO; offset++)
		irq_dispose_mapping(irq_find_mapping(tc_domain, offset));
	irq_domain_remove(tc_domain);
}

module_init(tc_init);
module_exit(tc_exit);

MODULE_DESCRIPTION("Parameter-driven test GPIO chip for guest tests");
MODULE_LICENSE("GPL");
