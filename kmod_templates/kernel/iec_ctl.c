// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_ctl.c - the configuration's control plane: what its two interfaces
 * share, and their registration.
 *
 *   iec_ctl.c        the privilege model's monitor group, iec_ctl_mutex,
 *                    resource and task start/stop, init and exit
 *   iec_ctl_nl.c     the generic netlink family "iec2kmod" and its commands
 *   iec_ctl_sysfs.c  /sys/kernel/iec2kmod/<configuration>/{status,control}
 *   iec_vars.c       the variable commands and the force lists
 *
 * The privilege model: every netlink command, every control write and
 * every status read needs CAP_NET_ADMIN (in the initial user namespace),
 * checked by the kernel on the operation, not only by a file mode.  One
 * read-only role beside it, off unless the module is loaded with
 * monitor_gid=GID: members of that group may read (IEC_CMD_STATUS,
 * IEC_CMD_VAR_GET, IEC_CMD_VAR_LIST, the status file) and nothing else.
 *
 * Netlink commands and control writes run one at a time (iec_ctl_mutex);
 * they may sleep, but never while holding a raw lock.
 */
#include <linux/cred.h>
#include <linux/lockdep.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/string.h>
#include <net/genetlink.h>

#include "iec_kmod.h"
#include "iec_ctl.h"
#include "iec_nl.h"

/* serialises netlink commands, sysfs control and the force lists */
DEFINE_MUTEX(iec_ctl_mutex);

/* 0444: fixed at load (a writable parameter would be a second way in) */
static int monitor_gid = -1;
module_param(monitor_gid, int, 0444);
MODULE_PARM_DESC(monitor_gid,
		 "group that may read status and variables without CAP_NET_ADMIN (default -1: none)");

/* The caller is in the read-only monitor group (monitor_gid). */
bool iec_monitor(void)
{
	kgid_t gid;

	if (monitor_gid < 0)
		return false;
	gid = make_kgid(&init_user_ns, monitor_gid);
	return gid_valid(gid) && in_group_p(gid);
}

/* The task "<resource>.<task>" names, or NULL; *r is its resource. */
static struct iec_task *iec_task_find(const char *name, struct iec_resource **r)
{
	const char *dot = strchr(name, '.');
	struct iec_resource *res;
	u32 i;

	if (!dot)
		return NULL;
	list_for_each_entry(res, &iec_resources, node) {
		if (strlen(res->name) != dot - name ||
		    strncasecmp(name, res->name, dot - name))
			continue;
		for (i = 0; i < res->ntasks; i++) {
			if (!strcasecmp(dot + 1, res->tasks[i].name)) {
				*r = res;
				return &res->tasks[i];
			}
		}
	}
	return NULL;
}

/*
 * start/stop one resource by name, or all of them (name NULL or "all");
 * start also takes one task, "<resource>.<task>" (a restart: the other
 * tasks of its resource are left as they are).
 * A stop returns once every task it stopped acknowledged (its thread is
 * idle: no cycle runs, the resource module may go), or -ETIMEDOUT after
 * the bound, naming the task that did not.  The caller holds iec_ctl_mutex.
 */
int iec_control_resource(const char *name, bool start, u32 run_ms)
{
	/* a common first release, late enough for every task to be asleep */
	ktime_t epoch = ktime_add_ms(ktime_get(), IEC_START_DELAY_MS);
	struct iec_resource *r;
	struct iec_task *t;
	unsigned long deadline;
	s64 longest = 0;
	int ret = -ENOENT;
	u32 i;

	lockdep_assert_held(&iec_ctl_mutex);
	if (name && !strcmp(name, "all"))
		name = NULL;
	mutex_lock(&iec_resources_lock);
	if (name && strchr(name, '.')) {
		t = iec_task_find(name, &r);
		if (t && start) {
			r->epoch = epoch;
			r->until = run_ms ? ktime_add_ms(epoch, run_ms) : 0;
			ret = r->start_task(r, t - r->tasks);
		} else if (t) {
			ret = -EOPNOTSUPP;	/* a stop is per resource */
		}
		mutex_unlock(&iec_resources_lock);
		return ret;
	}
	list_for_each_entry(r, &iec_resources, node) {
		if (name && strcasecmp(name, r->name))
			continue;
		if (start) {
			r->epoch = epoch;
			r->until = run_ms ? ktime_add_ms(epoch, run_ms) : 0;
			ret = r->start(r);
		} else {
			r->stop(r);
			for (i = 0; i < r->ntasks; i++)
				longest = max(longest, r->tasks[i].interval_ns);
			ret = 0;
		}
		if (ret)
			break;
	}
	if (!start && !ret) {
		deadline = jiffies + iec2kmod_wait_bound(longest);
		list_for_each_entry(r, &iec_resources, node) {
			if (name && strcasecmp(name, r->name))
				continue;
			ret = iec_wait_resource_idle(r, deadline);
			if (ret)
				break;
		}
	}
	if (!name && list_empty(&iec_resources))
		ret = 0;	/* "all" of nothing */
	mutex_unlock(&iec_resources_lock);
	return ret;
}

int iec_ctl_init(void)
{
	int ret;

	ret = iec_ctl_sysfs_init();
	if (ret)
		return ret;
	ret = genl_register_family(&iec_nl_family);
	if (ret) {
		pr_err("iec2kmod: generic netlink family %s: error %d\n",
		       IEC_NL_FAMILY, ret);
		iec_ctl_sysfs_exit();
	}
	return ret;
}

void iec_ctl_exit(void)
{
	genl_unregister_family(&iec_nl_family);
	iec_ctl_sysfs_exit();
	/* no resource is left: only forced configuration globals remain */
	iec_vars_exit();
}
