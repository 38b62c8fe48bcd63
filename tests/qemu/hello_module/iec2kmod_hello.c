// SPDX-License-Identifier: GPL-2.0-only OR MIT
/* Smallest useful module for the QEMU and container test tiers. */
#include <linux/init.h>
#include <linux/module.h>
#include <linux/moduleparam.h>
#include <linux/printk.h>
#include <linux/bug.h>

static char *greeting = "hello";
module_param(greeting, charp, 0444);
MODULE_PARM_DESC(greeting, "word printed when the module is inserted");

/* for the harness's own tests: a kernel WARNING when the module is removed */
static bool warn_on_exit;
module_param(warn_on_exit, bool, 0444);
MODULE_PARM_DESC(warn_on_exit, "WARN_ON(1) in the exit path (tests of the log checks)");

static int __init iec2kmod_hello_init(void)
{
	pr_info("iec2kmod_hello: %s from the PREEMPT_RT guest\n", greeting);
	return 0;
}

static void __exit iec2kmod_hello_exit(void)
{
	pr_info("iec2kmod_hello: goodbye\n");
	WARN_ON(warn_on_exit);
}

module_init(iec2kmod_hello_init);
module_exit(iec2kmod_hello_exit);

MODULE_LICENSE("Dual MIT/GPL");
MODULE_AUTHOR("iec2kmod");
MODULE_DESCRIPTION("iec2kmod test-harness hello-world module");
