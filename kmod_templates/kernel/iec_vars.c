// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_vars.c - variable access of the configuration's control plane: the
 * netlink commands VAR_GET, VAR_LIST, VAR_SET, VAR_FORCE and VAR_UNFORCE
 * (in iec_ctl_nl.c's command table, under iec_ctl_mutex) and the force lists
 * the real-time tasks apply at their cycle boundaries.
 *
 * Variable access and the real-time tasks:
 *  - globals (configuration, resource and process image) are read and
 *    written under the image lock, the raw spinlock of copy-in/copy-out,
 *    so a task sees a manager write whole, at its next copy-in; a write
 *    that raises a SINGLE variable wakes its event tasks;
 *  - program-instance variables belong to the task that runs the
 *    instance; the manager touches them only between two cycles of that
 *    task: under the task's var_lock with in_cycle false (the task sets it
 *    under the same lock at both ends of a cycle).  While a cycle runs,
 *    the command waits for its end (iec_ack_wq) holding no lock and no
 *    mutex: it counts itself in the resource's users instead, which
 *    unregistering waits for (one request waits at most
 *    IEC_BOUNDARY_WAIT_MS in all), so other commands and the tasks never
 *    wait for it; the task
 *    never waits longer than one memcpy of one variable;
 *  - the kernel checks every value it stores (iec_value_check()): its
 *    size, a BOOL's 0/1, a string's length against its declared capacity,
 *    a subrange's bounds, an enumeration's value set; read-only variables
 *    (CONSTANT, FB outputs, SFC steps) refuse writes and forces.  A request
 *    naming a variable twice is refused;
 *  - forced variables keep their forced value at cycle boundaries: forced
 *    globals are written back after every copy-out (under the image lock,
 *    so no task ever copies in an unforced value); forced instance
 *    variables are written at both ends of every cycle of their task.
 *    Forcing an instance variable that a program connection assigns
 *    (an input) has no lasting effect: force the global or the %I
 *    address it is connected to.  A task that writes a forced SINGLE
 *    variable may still wake its event tasks: the edge is detected in the
 *    copy-out before the forced value is written back.
 */
#include <linux/delay.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/overflow.h>
#include <linux/sched.h>
#include <linux/sched/signal.h>
#include <linux/slab.h>
#include <linux/string.h>
#include <linux/timekeeping.h>
#include <asm/unaligned.h>
#include <net/genetlink.h>

#include "iec_kmod.h"
#include "iec_ctl.h"
#include "iec_nl.h"

/* forced globals: changed under iec_ctl_mutex and the image lock, walked
 * under the image lock */
static struct iec_force *iec_global_forces;

/* ------------------------------------------------------------------ */
/* forces, called from the real-time tasks                            */
/* ------------------------------------------------------------------ */

static void iec_forces_write(const struct iec_force *f)
{
	for (; f; f = f->next)
		memcpy(f->desc->addr, f->value, f->size);
}

void iec2kmod_cycle_begin(struct iec_task *t)
{
	ktime_t now = ktime_get();

	raw_spin_lock(&t->var_lock);
	iec_forces_write(t->forces);
	t->in_cycle = true;
	WRITE_ONCE(t->cycle_start, now);
	WRITE_ONCE(t->cycle_seq, t->cycle_seq + 1);	/* odd: in a cycle */
	raw_spin_unlock(&t->var_lock);
}
EXPORT_SYMBOL_GPL(iec2kmod_cycle_begin);

void iec2kmod_cycle_end(struct iec_task *t)
{
	raw_spin_lock(&t->var_lock);
	iec_forces_write(t->forces);
	t->in_cycle = false;
	/* the cycle's body calls before the grace period sees it end */
	smp_store_release(&t->cycle_seq, t->cycle_seq + 1);
	raw_spin_unlock(&t->var_lock);
	if (wq_has_sleeper(&iec_ack_wq))
		wake_up_all(&iec_ack_wq);
}
EXPORT_SYMBOL_GPL(iec2kmod_cycle_end);

/* The caller holds the image lock (a task's copy-out). */
void iec2kmod_force_globals(void)
{
	iec_forces_write(iec_global_forces);
}
EXPORT_SYMBOL_GPL(iec2kmod_force_globals);

static void iec_forces_free(struct iec_force *f)
{
	while (f) {
		struct iec_force *next = f->next;

		kfree(f);
		f = next;
	}
}

/* Unlinks the force of @desc from the list at @pp; returns it or NULL. */
static struct iec_force *iec_force_unlink(struct iec_force **pp,
					  const struct iec_var_desc *desc)
{
	struct iec_force *f;

	for (; (f = *pp); pp = &f->next) {
		if (f->desc == desc) {
			*pp = f->next;
			f->next = NULL;
			return f;
		}
	}
	return NULL;
}

/*
 * Resource exit, after it unregistered and its threads stopped: drops the
 * forces that point into the resource module (its globals, its instances).
 */
void iec2kmod_resource_gone(struct iec_resource *res)
{
	struct iec_force *drop = NULL, *f, **pp;
	u32 i;

	mutex_lock(&iec_ctl_mutex);
	iec2kmod_image_lock();
	for (pp = &iec_global_forces; (f = *pp);) {
		if (f->res == res) {
			*pp = f->next;
			f->next = drop;
			drop = f;
		} else {
			pp = &f->next;
		}
	}
	iec2kmod_image_unlock();
	for (i = 0; i < res->ntasks; i++) {
		struct iec_task *t = &res->tasks[i];

		raw_spin_lock(&t->var_lock);
		f = t->forces;
		t->forces = NULL;
		raw_spin_unlock(&t->var_lock);
		iec_forces_free(f);
	}
	mutex_unlock(&iec_ctl_mutex);
	iec_forces_free(drop);
}
EXPORT_SYMBOL_GPL(iec2kmod_resource_gone);

/* ------------------------------------------------------------------ */
/* variables                                                          */
/* ------------------------------------------------------------------ */

struct iec_var_ref {
	const struct iec_var_desc *desc;
	struct iec_resource *res;	/* NULL: the configuration's table */
	struct iec_task *task;		/* NULL: a global */
	u32 index;
	const struct nlattr *value;	/* VALUE of a write or force */
	bool pinned;			/* counted in res->users */
	u16 raised;			/* 1 + event: the write raised a SINGLE variable */
	void *out;			/* VAR_GET: where the value goes */
};

/*
 * A string attribute must end exactly at its NUL: "plc.ticks\0garbage" is
 * refused (the policy's NLA_NUL_STRING only asks for a NUL somewhere).
 */
int iec_nla_strict_string(const struct nlattr *a, struct netlink_ext_ack *extack)
{
	if (a && strnlen(nla_data(a), nla_len(a)) + 1 != nla_len(a)) {
		NL_SET_ERR_MSG_ATTR(extack, a, "bytes after the string's NUL");
		return -EINVAL;
	}
	return 0;
}

static void iec_var_ref_set(struct iec_var_ref *ref, struct iec_resource *res,
			    const struct iec_var_desc *vars, u32 i)
{
	ref->desc = &vars[i];
	ref->res = res;
	ref->index = i;
	ref->task = NULL;
	if (res && vars[i].task && vars[i].task <= res->ntasks)
		ref->task = &res->tasks[vars[i].task - 1];
}

static struct iec_resource *iec_resource_find(const char *name)
{
	struct iec_resource *r;

	lockdep_assert_held(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node)
		if (!strcasecmp(r->name, name))
			return r;
	return NULL;
}

/* IEC names are case-insensitive: so are variable paths. */
static int iec_var_find(const char *path, struct iec_var_ref *ref)
{
	struct iec_resource *r;
	u32 i;

	lockdep_assert_held(&iec_resources_lock);
	for (i = 0; i < iec_cfg->nvars; i++) {
		if (!strcasecmp(iec_cfg->vars[i].path, path)) {
			iec_var_ref_set(ref, NULL, iec_cfg->vars, i);
			return 0;
		}
	}
	list_for_each_entry(r, &iec_resources, node) {
		for (i = 0; i < r->nvars; i++) {
			if (!strcasecmp(r->vars[i].path, path)) {
				iec_var_ref_set(ref, r, r->vars, i);
				return 0;
			}
		}
	}
	return -ENOENT;
}

static const struct nla_policy iec_nl_sel_policy[IEC_A_MAX + 1] = {
	[IEC_A_PATH] = { .type = NLA_NUL_STRING, .len = 511 },
	[IEC_A_TABLE] = { .type = NLA_NUL_STRING, .len = 63 },
	[IEC_A_INDEX] = { .type = NLA_U32 },
};

static const struct nla_policy iec_nl_val_policy[IEC_A_MAX + 1] = {
	[IEC_A_PATH] = { .type = NLA_NUL_STRING, .len = 511 },
	[IEC_A_TABLE] = { .type = NLA_NUL_STRING, .len = 63 },
	[IEC_A_INDEX] = { .type = NLA_U32 },
	[IEC_A_VALUE] = { .type = NLA_BINARY, .len = IEC_NL_VALUE_MAX },
};

/* A VAR nest: PATH, or TABLE and INDEX (and PATH, which must agree). */
static int iec_var_select(const struct nlattr *nest,
			  const struct nla_policy *policy,
			  struct iec_var_ref *ref, struct netlink_ext_ack *extack)
{
	struct nlattr *tb[IEC_A_MAX + 1];
	int err;

	err = nla_parse_nested(tb, IEC_A_MAX, nest, policy, extack);
	if (err)
		return err;
	err = iec_nla_strict_string(tb[IEC_A_PATH], extack) ?:
	      iec_nla_strict_string(tb[IEC_A_TABLE], extack);
	if (err)
		return err;
	if (tb[IEC_A_TABLE] && tb[IEC_A_INDEX]) {
		const char *table = nla_data(tb[IEC_A_TABLE]);
		u32 i = nla_get_u32(tb[IEC_A_INDEX]);
		struct iec_resource *r = NULL;

		if (*table) {
			r = iec_resource_find(table);
			if (!r) {
				NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_TABLE],
						    "no such resource");
				return -ENOENT;
			}
		}
		if (i >= (r ? r->nvars : iec_cfg->nvars)) {
			NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_INDEX],
					    "variable index out of range");
			return -ENOENT;
		}
		iec_var_ref_set(ref, r, r ? r->vars : iec_cfg->vars, i);
		if (tb[IEC_A_PATH] &&
		    strcasecmp(ref->desc->path, nla_data(tb[IEC_A_PATH]))) {
			NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_PATH],
					    "variable index and path disagree");
			return -ESTALE;
		}
	} else if (tb[IEC_A_PATH]) {
		err = iec_var_find(nla_data(tb[IEC_A_PATH]), ref);
		if (err) {
			NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_PATH],
					    "no such variable");
			return err;
		}
	} else {
		NL_SET_ERR_MSG_ATTR(extack, nest,
				    "a variable needs PATH, or TABLE and INDEX");
		return -EINVAL;
	}
	ref->value = tb[IEC_A_VALUE];
	return 0;
}

/* The integer in @p (@size bytes, host order), sign-extended or not. */
static s64 iec_int_value(const u8 *p, u32 size, bool sign)
{
	switch (size) {
	case 1:
		return sign ? (s64)(s8)p[0] : (s64)p[0];
	case 2:
		return sign ? (s64)(s16)get_unaligned((const u16 *)p) :
			      (s64)get_unaligned((const u16 *)p);
	case 4:
		return sign ? (s64)(s32)get_unaligned((const u32 *)p) :
			      (s64)get_unaligned((const u32 *)p);
	default:
		return (s64)get_unaligned((const u64 *)p);
	}
}

/*
 * The kernel's own check of a VALUE written or forced into a variable,
 * from its descriptor (generated from the checked project): the size, a
 * BOOL's 0/1, a STRING[n]'s length against n (not against the C object,
 * which may have padding) with the characters free of NUL, a subrange's
 * bounds, an enumeration's value set.  plc-manager checks the same first.
 */
static int iec_value_check(const struct iec_var_ref *ref,
			   struct netlink_ext_ack *extack)
{
	const struct iec_var_desc *d = ref->desc;
	const u8 *p;
	u32 len, i;
	s64 v;

	if (!ref->value) {
		NL_SET_ERR_MSG(extack, "a value is missing");
		return -EINVAL;
	}
	p = nla_data(ref->value);
	len = nla_len(ref->value);
	if (d->kind == 's' || d->kind == 'w') {
		u32 cs = d->kind == 'w' ? 2 : 1;
		u32 n;

		if (len < 2 + cs)
			goto bad_size;
		n = get_unaligned((const u16 *)p);
		if (len != 2 + (n + 1) * cs || len > d->size)
			goto bad_size;
		if (n > d->cap) {
			NL_SET_ERR_MSG_ATTR(extack, ref->value,
					    "the string is longer than its declared length");
			return -EMSGSIZE;
		}
		for (i = 0; i <= n; i++) {
			bool nul = cs == 1 ? !p[2 + i] :
				   !get_unaligned((const u16 *)(p + 2 + 2 * i));

			if (nul != (i == n)) {
				NL_SET_ERR_MSG_ATTR(extack, ref->value,
						    "a string ends at its length, with one NUL");
				return -EINVAL;
			}
		}
		return 0;
	}
	if (len != d->size)
		goto bad_size;
	if (d->kind == 'b' && p[0] > 1) {
		NL_SET_ERR_MSG_ATTR(extack, ref->value, "a BOOL is 0 or 1");
		return -EINVAL;
	}
	if (d->check == IEC_VCHK_RANGE && d->kind == 'u') {
		u64 u = (u64)iec_int_value(p, len, false);

		if (u < d->range.u.lo || u > d->range.u.hi)
			goto bad_range;
	} else if (d->check == IEC_VCHK_RANGE) {
		v = iec_int_value(p, len, true);
		if (v < d->range.s.lo || v > d->range.s.hi)
			goto bad_range;
	} else if (d->check == IEC_VCHK_ENUM) {
		v = iec_int_value(p, len, true);
		for (i = 0; i < d->nenum; i++)
			if (d->enum_values[i] == v)
				return 0;
		NL_SET_ERR_MSG_ATTR(extack, ref->value,
				    "not a value of the enumeration");
		return -ERANGE;
	}
	return 0;

bad_range:
	NL_SET_ERR_MSG_ATTR(extack, ref->value, "out of the subrange");
	return -ERANGE;
bad_size:
	NL_SET_ERR_MSG_ATTR(extack, ref->value,
			    "value size does not fit the variable");
	return -EMSGSIZE;
}

/* The force of @desc in the list @f, or NULL. */
static const struct iec_force *iec_force_find(const struct iec_force *f,
					      const struct iec_var_desc *desc)
{
	for (; f; f = f->next)
		if (f->desc == desc)
			return f;
	return NULL;
}

/*
 * Copies @len bytes from @src to @dst under @t's var_lock at a cycle
 * boundary (no cycle running).  With @unless_forced, a write: refused with
 * -EBUSY if that variable is forced (checked under var_lock, under which
 * the task's force list changes).  Waits for the end of the cycle on
 * iec_ack_wq until @deadline (jiffies; one for the whole request,
 * IEC_BOUNDARY_WAIT_MS after its start), then -EBUSY.  The caller holds no
 * mutex and no lock: it counted itself in the resource's users
 * (iec_refs_pin()).  The task waits for at most the memcpy of this one
 * variable (at most IEC_NL_VALUE_MAX bytes).
 */
#define IEC_BOUNDARY_WAIT_MS	1000

static int iec_task_boundary_copy(struct iec_task *t, void *dst,
				  const void *src, u32 len,
				  const struct iec_var_desc *unless_forced,
				  unsigned long deadline)
{
	long left;

	might_sleep();
	for (;;) {
		raw_spin_lock(&t->var_lock);
		if (!t->in_cycle) {
			if (unless_forced && iec_force_find(t->forces, unless_forced)) {
				raw_spin_unlock(&t->var_lock);
				return -EBUSY;
			}
			memcpy(dst, src, len);
			/* selective blocks of the task see a write they do not compare */
			t->ctx.sel_epoch++;
			raw_spin_unlock(&t->var_lock);
			return 0;
		}
		raw_spin_unlock(&t->var_lock);
		left = (long)(deadline - jiffies);
		if (left <= 0)
			return -EBUSY;
		/* iec2kmod_cycle_end() wakes iec_ack_wq after clearing in_cycle */
		left = wait_event_interruptible_timeout(iec_ack_wq,
							!READ_ONCE(t->in_cycle),
							left);
		if (left < 0)
			return -EINTR;
	}
}

/*
 * Counts the request in the users of the resource of every instance
 * variable in @refs, so that their descriptors and tasks stay valid once
 * the caller dropped iec_resources_lock and iec_ctl_mutex (which it holds
 * here: the resources in @refs are registered): the waits for a cycle
 * boundary happen without them, and unregistering the resource waits for
 * the request instead (iec2kmod_unregister_resource()).
 */
static void iec_refs_pin(struct iec_var_ref *refs, u32 n)
{
	u32 i;

	lockdep_assert_held(&iec_resources_lock);
	for (i = 0; i < n; i++) {
		if (!refs[i].task)
			continue;
		atomic_inc(&refs[i].res->users);
		refs[i].pinned = true;
	}
}

static void iec_refs_free(struct iec_var_ref *refs, u32 n)
{
	u32 i;

	if (!refs)
		return;
	for (i = 0; i < n; i++)
		if (refs[i].pinned && atomic_dec_and_test(&refs[i].res->users))
			wake_up_all(&iec_ack_wq);
	kfree(refs);
}

static u32 iec_value_len(const struct iec_var_desc *d)
{
	return min_t(u32, d->size, IEC_NL_VALUE_MAX);
}

static bool iec_rises(const struct iec_var_desc *d, const void *value)
{
	return d->single_event && d->kind == 'b' && !*(const u8 *)d->addr &&
	       *(const u8 *)value;
}

static bool iec_var_forced(const struct iec_var_ref *ref)
{
	lockdep_assert_held(&iec_ctl_mutex);
	return iec_force_find(ref->task ? ref->task->forces : iec_global_forces,
			      ref->desc);
}

u32 iec_forced_count(void)
{
	const struct iec_force *f;
	struct iec_resource *r;
	u32 n = 0, i;

	for (f = iec_global_forces; f; f = f->next)
		n++;
	list_for_each_entry(r, &iec_resources, node)
		for (i = 0; i < r->ntasks; i++)
			for (f = r->tasks[i].forces; f; f = f->next)
				n++;
	return n;
}

/* ------------------------------------------------------------------ */
/* generic netlink: the variable commands                             */
/* ------------------------------------------------------------------ */

/* Attributes of one variable, without its value. */
static int iec_put_var(struct sk_buff *skb, const struct iec_var_ref *ref)
{
	const struct iec_var_desc *d = ref->desc;

	if (nla_put_string(skb, IEC_A_PATH, d->path) ||
	    nla_put_string(skb, IEC_A_TABLE, ref->res ? ref->res->name : "") ||
	    nla_put_u32(skb, IEC_A_INDEX, ref->index) ||
	    nla_put_u8(skb, IEC_A_KIND, d->kind) ||
	    nla_put_u32(skb, IEC_A_SIZE, d->size) ||
	    nla_put_u8(skb, IEC_A_WRITABLE, d->writable) ||
	    nla_put_u8(skb, IEC_A_FORCED, iec_var_forced(ref)) ||
	    nla_put_u32(skb, IEC_A_EVENT, d->single_event) ||
	    nla_put_u32(skb, IEC_A_TASK_INDEX, ref->task ? d->task : 0))
		return -EMSGSIZE;
	return 0;
}

static size_t iec_var_msg_size(const struct iec_var_ref *ref, bool value)
{
	const struct iec_var_desc *d = ref->desc;

	return nla_total_size(0) +
	       nla_total_size(strlen(d->path) + 1) +
	       nla_total_size(ref->res ? strlen(ref->res->name) + 1 : 1) +
	       7 * nla_total_size(sizeof(u32)) +
	       (value ? nla_total_size(iec_value_len(d)) : 0);
}

/*
 * Resolves every VAR nest of a request into refs[] (kcalloc'ed, *n set).
 * The caller holds iec_ctl_mutex and iec_resources_lock.
 */
static int iec_nl_vars(struct genl_info *info, const struct nla_policy *policy,
		       struct iec_var_ref **refs, u32 *n)
{
	const struct nlattr *a;
	u32 count = 0, i = 0, k;
	int rem, err;

	nla_for_each_attr(a, genlmsg_data(info->genlhdr),
			  genlmsg_len(info->genlhdr), rem)
		if (nla_type(a) == IEC_A_VAR)
			count++;
	*refs = NULL;
	*n = 0;
	if (!count)
		return 0;
	if (count > IEC_NL_MAX_VARS) {
		NL_SET_ERR_MSG(info->extack, "too many variables in one request");
		return -E2BIG;
	}
	*refs = kcalloc(count, sizeof(**refs), GFP_KERNEL);
	if (!*refs)
		return -ENOMEM;
	nla_for_each_attr(a, genlmsg_data(info->genlhdr),
			  genlmsg_len(info->genlhdr), rem) {
		if (nla_type(a) != IEC_A_VAR)
			continue;
		err = iec_var_select(a, policy, &(*refs)[i], info->extack);
		for (k = 0; !err && k < i; k++) {
			if ((*refs)[k].desc == (*refs)[i].desc) {
				NL_SET_ERR_MSG_ATTR(info->extack, a,
						    "a variable is named twice in one request");
				err = -EINVAL;
			}
		}
		if (err) {
			kfree(*refs);
			*refs = NULL;
			return err;
		}
		i++;
	}
	*n = count;
	return 0;
}

int iec_nl_var_get(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_var_ref *refs;
	struct sk_buff *msg = NULL;
	unsigned long deadline;
	size_t size = 0;
	void *hdr;
	u32 n = 0, i;
	int err = iec_nl_may_read(skb);

	if (err)
		return err;
	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	err = iec_nl_vars(info, iec_nl_sel_policy, &refs, &n);
	if (err)
		goto out_locked;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named");
		err = -EINVAL;
		goto out_locked;
	}
	iec_refs_pin(refs, n);
	for (i = 0; i < n; i++)
		size += iec_var_msg_size(&refs[i], true);
	err = -ENOMEM;
	msg = genlmsg_new(size, GFP_KERNEL);
	if (!msg)
		goto out_locked;
	err = -EMSGSIZE;
	hdr = genlmsg_put_reply(msg, info, &iec_nl_family, 0, IEC_CMD_VAR_GET);
	if (!hdr)
		goto out_locked;
	for (i = 0; i < n; i++) {
		const struct iec_var_desc *d = refs[i].desc;
		u32 len = iec_value_len(d);
		struct nlattr *nest, *val;

		nest = nla_nest_start(msg, IEC_A_VAR);
		if (!nest || iec_put_var(msg, &refs[i]))
			goto out_locked;
		val = nla_reserve(msg, IEC_A_VALUE, len);
		if (!val)
			goto out_locked;
		refs[i].out = nla_data(val);
		/* a global: whole, under the image lock (one variable a hold) */
		if (!refs[i].task) {
			iec2kmod_image_lock();
			memcpy(refs[i].out, d->addr, len);
			iec2kmod_image_unlock();
		}
		nla_nest_end(msg, nest);
	}
	genlmsg_end(msg, hdr);
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	/* instance variables: at a boundary of their task, no mutex held */
	deadline = jiffies + msecs_to_jiffies(IEC_BOUNDARY_WAIT_MS);
	for (i = 0; i < n; i++) {
		if (!refs[i].task)
			continue;
		err = iec_task_boundary_copy(refs[i].task, refs[i].out,
					     refs[i].desc->addr,
					     iec_value_len(refs[i].desc), NULL,
					     deadline);
		if (err) {
			NL_SET_ERR_MSG(info->extack, "the task stays inside a cycle");
			goto out;
		}
	}
	iec_refs_free(refs, n);
	return genlmsg_reply(msg, info);

out_locked:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
out:
	nlmsg_free(msg);
	iec_refs_free(refs, n);
	return err;
}

/* Dump: one message per variable; cb->args: table (0 configuration,
 * 1.. the resources in order), index in it. */
int iec_nl_var_list(struct sk_buff *skb, struct netlink_callback *cb)
{
	long table = cb->args[0], idx = cb->args[1];

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	for (;; table++, idx = 0) {
		const struct iec_var_desc *vars = iec_cfg->vars;
		struct iec_resource *r = NULL;
		u32 n = iec_cfg->nvars;

		if (table > 0) {
			long k = 1;

			list_for_each_entry(r, &iec_resources, node)
				if (k++ == table)
					break;
			if (list_entry_is_head(r, &iec_resources, node))
				break;
			vars = r->vars;
			n = r->nvars;
		}
		for (; idx < n; idx++) {
			struct iec_var_ref ref;
			void *hdr;

			iec_var_ref_set(&ref, r, vars, idx);
			hdr = genlmsg_put(skb, NETLINK_CB(cb->skb).portid,
					  cb->nlh->nlmsg_seq, &iec_nl_family,
					  NLM_F_MULTI, IEC_CMD_VAR_LIST);
			if (!hdr)
				goto full;
			if (iec_put_var(skb, &ref)) {
				genlmsg_cancel(skb, hdr);
				goto full;
			}
			genlmsg_end(skb, hdr);
		}
	}
full:
	cb->args[0] = table;
	cb->args[1] = idx;
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	return skb->len;
}

/*
 * The bound of an image-lock hold of a command: a hold copies whole
 * variables, and takes the next one only while the hold stays within
 * IEC_IMAGE_HOLD_BYTES; a variable larger than that is copied alone.  So a
 * command holds the image lock (a raw spinlock: the tasks' copy-in and
 * copy-out wait for it) for at most max(IEC_IMAGE_HOLD_BYTES, one
 * variable) bytes of memcpy, one variable being at most IEC_NL_VALUE_MAX
 * (65000) bytes, a STRING[65000]: every elementary variable is at most 8
 * bytes, so a write of 256 elementary variables takes at most
 * 256 * 8 / 512 = 4 holds of at most 512 bytes each.  Each variable is
 * written whole (a task sees its old or its new value); a request's
 * globals may reach the tasks in several holds.
 * The other holds of the control plane: a read copies one variable a
 * hold; a force or unforce links or unlinks one force (and writes one
 * variable); the tasks' copy-out writes at most IEC_NL_MAX_FORCES forced
 * globals (iec2kmod_force_globals()).
 */
#define IEC_IMAGE_HOLD_BYTES	512

int iec_nl_var_set(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_var_ref *refs;
	unsigned long deadline;
	u32 n = 0, i;
	int err;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	err = iec_nl_vars(info, iec_nl_val_policy, &refs, &n);
	if (err)
		goto out_locked;
	err = -EINVAL;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named");
		goto out_locked;
	}
	/* everything is checked before anything is written */
	for (i = 0; i < n; i++) {
		err = iec_value_check(&refs[i], info->extack);
		if (err)
			goto out_locked;
		if (!refs[i].desc->writable) {
			NL_SET_ERR_MSG(info->extack, "the variable is read-only");
			err = -EACCES;
			goto out_locked;
		}
		if (iec_var_forced(&refs[i])) {
			NL_SET_ERR_MSG(info->extack, "the variable is forced");
			err = -EBUSY;
			goto out_locked;
		}
	}
	iec_refs_pin(refs, n);
	/* the globals, in holds bounded by IEC_IMAGE_HOLD_BYTES */
	i = 0;
	while (i < n) {
		u32 held = 0;

		if (refs[i].task) {
			i++;
			continue;
		}
		iec2kmod_image_lock();
		for (; i < n; i++) {
			const struct iec_var_desc *d = refs[i].desc;
			const void *v = nla_data(refs[i].value);
			u32 len = nla_len(refs[i].value);

			if (refs[i].task)
				continue;
			if (held && held + len > IEC_IMAGE_HOLD_BYTES)
				break;
			if (iec_rises(d, v))
				refs[i].raised = d->single_event;
			memcpy(d->addr, v, len);
			held += len;
		}
		iec2kmod_image_unlock();
		cond_resched();
	}
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	/* every raised SINGLE variable wakes its event tasks, however many */
	for (i = 0; i < n; i++)
		if (refs[i].raised)
			iec2kmod_event(refs[i].raised - 1);
	/*
	 * instance variables, each between two cycles of its task, with no
	 * mutex held (a force that came meanwhile wins: -EBUSY)
	 */
	deadline = jiffies + msecs_to_jiffies(IEC_BOUNDARY_WAIT_MS);
	for (i = 0; i < n && !err; i++) {
		struct iec_task *t = refs[i].task;

		if (!t)
			continue;
		err = iec_task_boundary_copy(t, refs[i].desc->addr,
					     nla_data(refs[i].value),
					     nla_len(refs[i].value), refs[i].desc,
					     deadline);
	}
	if (err)
		NL_SET_ERR_MSG(info->extack,
			       "the task stays inside a cycle, or the variable was forced");
	iec_refs_free(refs, n);
	return err;

out_locked:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	iec_refs_free(refs, n);
	return err;
}

int iec_nl_var_force(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_force **forces = NULL;
	struct iec_var_ref *refs;
	u32 n, i, added = 0;
	int err;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	err = iec_nl_vars(info, iec_nl_val_policy, &refs, &n);
	if (err)
		goto out;
	err = -EINVAL;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named");
		goto out;
	}
	for (i = 0; i < n; i++) {
		err = iec_value_check(&refs[i], info->extack);
		if (err)
			goto out;
		/* a constant, an FB output, a step: not even forced */
		if (!refs[i].desc->writable) {
			NL_SET_ERR_MSG(info->extack, "the variable is read-only");
			err = -EACCES;
			goto out;
		}
		/* no duplicate in refs[] (iec_nl_vars()): each counts once */
		if (!iec_var_forced(&refs[i]))
			added++;
	}
	/* each force costs the tasks a copy at every cycle boundary */
	if (iec_forced_count() + added > IEC_NL_MAX_FORCES) {
		NL_SET_ERR_MSG(info->extack, "too many forced variables");
		err = -ENOSPC;
		goto out;
	}
	err = -ENOMEM;
	forces = kcalloc(n, sizeof(*forces), GFP_KERNEL);
	if (!forces)
		goto out;
	for (i = 0; i < n; i++) {
		u32 len = nla_len(refs[i].value);

		forces[i] = kzalloc(struct_size(forces[i], value, len), GFP_KERNEL);
		if (!forces[i])
			goto out;
		forces[i]->desc = refs[i].desc;
		forces[i]->res = refs[i].res;
		forces[i]->size = len;
		memcpy(forces[i]->value, nla_data(refs[i].value), len);
	}
	/* one force (one variable's memcpy) per lock hold */
	for (i = 0; i < n; i++) {
		struct iec_force *f = forces[i], *old;
		struct iec_task *t = refs[i].task;
		bool rise = false;

		if (t) {
			raw_spin_lock(&t->var_lock);
			old = iec_force_unlink(&t->forces, f->desc);
			f->next = t->forces;
			t->forces = f;
			if (!t->in_cycle)
				memcpy(f->desc->addr, f->value, f->size);
			t->ctx.sel_epoch++;	/* selective blocks: a new value */
			raw_spin_unlock(&t->var_lock);
		} else {
			iec2kmod_image_lock();
			old = iec_force_unlink(&iec_global_forces, f->desc);
			rise = iec_rises(f->desc, f->value);
			f->next = iec_global_forces;
			iec_global_forces = f;
			memcpy(f->desc->addr, f->value, f->size);
			iec2kmod_image_unlock();
		}
		forces[i] = NULL;
		kfree(old);
		if (rise)
			iec2kmod_event(f->desc->single_event - 1);
	}
	err = 0;
out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	if (forces)
		for (i = 0; i < n; i++)
			kfree(forces[i]);
	kfree(forces);
	kfree(refs);
	return err;
}

const struct nla_policy iec_nl_unforce_policy[IEC_A_MAX + 1] = {
	[IEC_A_VAR] = NLA_POLICY_NESTED(iec_nl_sel_policy),
	[IEC_A_ALL] = { .type = NLA_FLAG },
};

int iec_nl_var_unforce(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_force *drop = NULL, *f;
	struct iec_var_ref *refs = NULL;
	struct iec_resource *r;
	u32 n = 0, i;
	int err = 0;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	if (info->attrs[IEC_A_ALL]) {
		iec2kmod_image_lock();
		drop = iec_global_forces;
		iec_global_forces = NULL;
		iec2kmod_image_unlock();
		iec_forces_free(drop);
		list_for_each_entry(r, &iec_resources, node) {
			for (i = 0; i < r->ntasks; i++) {
				struct iec_task *t = &r->tasks[i];

				raw_spin_lock(&t->var_lock);
				drop = t->forces;
				t->forces = NULL;
				raw_spin_unlock(&t->var_lock);
				iec_forces_free(drop);
			}
		}
		goto out;
	}
	err = iec_nl_vars(info, iec_nl_sel_policy, &refs, &n);
	if (err)
		goto out;
	err = -EINVAL;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named (or ALL)");
		goto out;
	}
	for (i = 0; i < n; i++) {
		if (!iec_var_forced(&refs[i])) {
			NL_SET_ERR_MSG(info->extack, "the variable is not forced");
			err = -ENODATA;
			goto out;
		}
	}
	for (i = 0; i < n; i++) {
		struct iec_task *t = refs[i].task;

		if (t) {
			raw_spin_lock(&t->var_lock);
			f = iec_force_unlink(&t->forces, refs[i].desc);
			raw_spin_unlock(&t->var_lock);
		} else {
			iec2kmod_image_lock();
			f = iec_force_unlink(&iec_global_forces, refs[i].desc);
			iec2kmod_image_unlock();
		}
		kfree(f);
	}
	err = 0;
out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	kfree(refs);
	return err;
}

const struct nla_policy iec_nl_get_policy[IEC_A_MAX + 1] = {
	[IEC_A_VAR] = NLA_POLICY_NESTED(iec_nl_sel_policy),
};

const struct nla_policy iec_nl_set_policy[IEC_A_MAX + 1] = {
	[IEC_A_VAR] = NLA_POLICY_NESTED(iec_nl_val_policy),
};

/* after the last resource is gone: only forced configuration globals remain */
void iec_vars_exit(void)
{
	iec_forces_free(iec_global_forces);
	iec_global_forces = NULL;
}
