// SPDX-License-Identifier: GPL-2.0
/*
 * TEST-ONLY kernel module for weedspray's QEMU harness (tests/vm). Never load it on a sprayer.
 *
 * It binds the kernel's interrupt-cnt counter driver to one gpio-sim line on x86, where there
 * is no device tree. On a real board the device tree does this job (a node with
 * compatible = "interrupt-counter" and gpios = <&gpio N 0>, see tests/vm/README.md).
 *
 * How (Linux 6.1): it registers a platform device named after the driver, because without an
 * OF or ACPI node platform_match() falls back to comparing the device name with the driver
 * name ("interrupt-cnt"; "interrupt-counter" is only the DT compatible and the module alias).
 * A gpiod lookup table for that device hands interrupt-cnt the line chip_label:line; the
 * device has no IRQ resource, so platform_get_irq_optional() returns -ENXIO and interrupt-cnt
 * takes the line's interrupt from gpiod_to_irq().
 *
 *   insmod interrupt_counter_fixture.ko chip_label=weedspray-count line=0
 */
#include <linux/device.h>
#include <linux/err.h>
#include <linux/gpio/machine.h>
#include <linux/module.h>
#include <linux/moduleparam.h>
#include <linux/platform_device.h>

#define FIXTURE_DRIVER_NAME "interrupt-cnt"

static char *chip_label = "weedspray-count";
module_param(chip_label, charp, 0444);
MODULE_PARM_DESC(chip_label, "label of the GPIO chip that carries the counted line");

static ushort line;
module_param(line, ushort, 0444);
MODULE_PARM_DESC(line, "offset of the counted line on that chip");

/* dev_id is dev_name() of a PLATFORM_DEVID_NONE device: its bare name. */
static struct gpiod_lookup_table fixture_lookup = {
	.dev_id = FIXTURE_DRIVER_NAME,
	.table = {
		GPIO_LOOKUP("filled in at load", 0, NULL, GPIO_ACTIVE_HIGH),
		{},
	},
};

static struct platform_device *fixture_device;

static int __init interrupt_counter_fixture_init(void)
{
	fixture_lookup.table[0].key = chip_label;
	fixture_lookup.table[0].chip_hwnum = line;
	gpiod_add_lookup_table(&fixture_lookup);

	fixture_device = platform_device_register_simple(FIXTURE_DRIVER_NAME, PLATFORM_DEVID_NONE,
							 NULL, 0);
	if (IS_ERR(fixture_device)) {
		gpiod_remove_lookup_table(&fixture_lookup);
		return PTR_ERR(fixture_device);
	}
	/*
	 * interrupt-cnt probes synchronously during the registration. A device left unbound
	 * (chip not found: probe deferred; line busy) would make the harness fail much later
	 * and less clearly, so refuse to load instead.
	 */
	if (!fixture_device->dev.driver) {
		pr_err("interrupt_counter_fixture: interrupt-cnt did not bind to %s line %u (is interrupt-cnt loaded and the chip live? see the messages above)\n",
		       chip_label, line);
		platform_device_unregister(fixture_device);
		gpiod_remove_lookup_table(&fixture_lookup);
		return -ENODEV;
	}
	return 0;
}

static void __exit interrupt_counter_fixture_exit(void)
{
	platform_device_unregister(fixture_device);
	gpiod_remove_lookup_table(&fixture_lookup);
}

module_init(interrupt_counter_fixture_init);
module_exit(interrupt_counter_fixture_exit);

MODULE_DESCRIPTION("TEST ONLY: binds interrupt-cnt to a gpio-sim line (weedspray tests/vm)");
MODULE_LICENSE("GPL");
