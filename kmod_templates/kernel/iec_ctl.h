/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_ctl.h - between the two halves of the configuration's control plane,
 * inside the configuration module: iec_ctl.c (status, control, sysfs, the
 * generic netlink family and its command table) and iec_vars.c (the
 * variable commands and the force lists).
 */
#ifndef IEC_CTL_H
#define IEC_CTL_H

#include <linux/mutex.h>
#include <net/genetlink.h>

#include "iec_nl.h"

/* serialises netlink commands, sysfs control and the force lists */
extern struct mutex iec_ctl_mutex;
extern struct genl_family iec_nl_family;

/* iec_vars.c: the variable commands, under iec_ctl_mutex */
extern const struct nla_policy iec_nl_get_policy[IEC_A_MAX + 1];
extern const struct nla_policy iec_nl_set_policy[IEC_A_MAX + 1];
extern const struct nla_policy iec_nl_unforce_policy[IEC_A_MAX + 1];
int iec_nl_var_get(struct sk_buff *skb, struct genl_info *info);
int iec_nl_var_list(struct sk_buff *skb, struct netlink_callback *cb);
int iec_nl_var_set(struct sk_buff *skb, struct genl_info *info);
int iec_nl_var_force(struct sk_buff *skb, struct genl_info *info);
int iec_nl_var_unforce(struct sk_buff *skb, struct genl_info *info);

/* 0 if the sender of @skb may read (CAP_NET_ADMIN or monitor_gid), else -EPERM */
int iec_nl_may_read(const struct sk_buff *skb);
/* -EINVAL unless the string attribute @a (or NULL) ends exactly at its NUL */
int iec_nla_strict_string(const struct nlattr *a, struct netlink_ext_ack *extack);
/* the number of forced variables (the caller holds iec_ctl_mutex) */
u32 iec_forced_count(void);
/* frees the forced configuration globals, when no resource is left */
void iec_vars_exit(void);

#endif /* IEC_CTL_H */
