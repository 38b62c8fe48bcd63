/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_ctl.h - between the parts of the configuration's control plane,
 * inside the configuration module: iec_ctl.c (what the two interfaces
 * share: the monitor group, iec_ctl_mutex, resource start/stop; init and
 * exit), iec_ctl_nl.c (the generic netlink family and its command table),
 * iec_ctl_sysfs.c (the status and control files) and iec_vars.c (the
 * variable commands and the force lists).  Nothing here is exported.
 */
#ifndef IEC_CTL_H
#define IEC_CTL_H

#include <linux/mutex.h>
#include <linux/types.h>
#include <net/genetlink.h>

#include "iec_nl.h"

/* iec_ctl.c: serialises netlink commands, sysfs control and the force lists */
extern struct mutex iec_ctl_mutex;
/* the caller is in the read-only monitor group (module parameter monitor_gid) */
bool iec_monitor(void);
/*
 * start (@run_ms: 0, or a run that ends by itself) or stop resource @name,
 * every resource (NULL or "all"), or start task "<resource>.<task>"; under
 * iec_ctl_mutex.  -ENOENT: no such name; -EOPNOTSUPP: a task stop;
 * -ETIMEDOUT: a stopped task did not come back from its cycle in time;
 * or the error of a resource's start
 */
int iec_control_resource(const char *name, bool start, u32 run_ms);

/* iec_ctl_nl.c */
extern struct genl_family iec_nl_family;
/* 0 if the sender of @skb may read (CAP_NET_ADMIN or monitor_gid), else -EPERM */
int iec_nl_may_read(const struct sk_buff *skb);

/* iec_ctl_sysfs.c: the status and control files, made by iec_ctl_init() */
int iec_ctl_sysfs_init(void);
void iec_ctl_sysfs_exit(void);

/* iec_vars.c: the variable commands, under iec_ctl_mutex */
extern const struct nla_policy iec_nl_get_policy[IEC_A_MAX + 1];
extern const struct nla_policy iec_nl_set_policy[IEC_A_MAX + 1];
extern const struct nla_policy iec_nl_unforce_policy[IEC_A_MAX + 1];
int iec_nl_var_get(struct sk_buff *skb, struct genl_info *info);
int iec_nl_var_list(struct sk_buff *skb, struct netlink_callback *cb);
int iec_nl_var_set(struct sk_buff *skb, struct genl_info *info);
int iec_nl_var_force(struct sk_buff *skb, struct genl_info *info);
int iec_nl_var_unforce(struct sk_buff *skb, struct genl_info *info);

/* -EINVAL unless the string attribute @a (or NULL) ends exactly at its NUL */
int iec_nla_strict_string(const struct nlattr *a, struct netlink_ext_ack *extack);
/* the number of forced variables (the caller holds iec_ctl_mutex) */
u32 iec_forced_count(void);
/* frees the forced configuration globals, when no resource is left */
void iec_vars_exit(void);

#endif /* IEC_CTL_H */
