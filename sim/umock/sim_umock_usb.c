/* SPDX-License-Identifier: MIT */
/* sim_umock_usb.c: the USB trigger/encoder box (1209:cf01, docs/rig-usb.md)
 * as a live usbdevfs ioctl handler: URBs submitted by an unmodified libusb
 * program are queued and completed on reap (control IN/OUT from the vendor
 * protocol and the standard descriptor requests, bulk IN encoder packets
 * at the armed trigger period, bulk OUT accepted); a discarded URB (libusb's
 * timeout) reaps with -ENOENT. Faults: silence, unplug, bad CRC, gaps. */
#include "hal_trig.h"
#include "sim_umock.h"
#include <errno.h>
#include <linux/usbdevice_fs.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>

#define USBDEV "/devices/pci0000:00/0000:00:14.0/usb1/1-2"

static const uint8_t dev_desc[18] = {0x12, 0x01, 0x00, 0x02, 0xFF, 0x00, 0x00, 0x40, 0x09,
                                     0x12, 0x01, 0xCF, 0x00, 0x01, 0x01, 0x02, 0x03, 0x01};
static const uint8_t cfg_desc[32] = {
    0x09, 0x02, 0x20,        0x00, 0x01, 0x01, 0x00, 0x80, 0x32, /* configuration 1 */
    0x09, 0x04, 0x00,        0x00, 0x02, 0xFF, 0x00, 0x00, 0x00, /* interface 0, vendor */
    0x07, 0x05, TRIG_EP_IN,  0x02, 0x40, 0x00, 0x00,             /* bulk IN, 64 */
    0x07, 0x05, TRIG_EP_OUT, 0x02, 0x40, 0x00, 0x00};            /* bulk OUT, 64 */
static const char *const strings[] = {NULL, "cellfit", "trigger box", "TB000042"};
#define SERIAL_NO 42u

/* A format: the device number (%1$d) changes at every plug, as on a real bus. */
static const char desc_fmt[] = "P: " USBDEV "\n"
                               "N: bus/usb/001/%1$03d\n"
                               "E: SUBSYSTEM=usb\n"
                               "E: DEVNAME=/dev/bus/usb/001/%1$03d\n"
                               "E: DEVTYPE=usb_device\n"
                               "E: DRIVER=usb\n"
                               "E: BUSNUM=001\n"
                               "E: DEVNUM=%1$03d\n"
                               "E: ID_VENDOR_ID=1209\n"
                               "E: ID_MODEL_ID=cf01\n"
                               "A: busnum=1\n"
                               "A: devnum=%1$d\n"
                               "A: idVendor=1209\n"
                               "A: idProduct=cf01\n"
                               "A: manufacturer=cellfit\n"
                               "A: product=trigger box\n"
                               "A: serial=TB000042\n"
                               "A: speed=480\n"
                               "A: bConfigurationValue=1\n"
                               "A: bNumInterfaces= 1\n"
                               "A: dev=189:%1$d\n"
                               "H: descriptors=12010002FF000040091201CF0001010203010902200001010080"
                               "320904000002FF0000000705810240000007050102400000\n"
                               "\n"
                               "P: " USBDEV "/1-2:1.0\n"
                               "E: SUBSYSTEM=usb\n"
                               "E: DEVTYPE=usb_interface\n"
                               "A: bInterfaceNumber=00\n"
                               "A: bInterfaceClass=ff\n";

typedef struct urb {
    UMockdevIoctlData *urb, *buf; /* our copies of the client's URB and buffer */
    gulong addr;                  /* the client's URB address (discard) */
    int ready;                    /* control / OUT: completed at submit */
} urb_t;

#define MAX_URBS 64

static struct {
    GMutex lock;
    UMockdevTestbed *tb;
    const sim_usb_cfg_t *cfg;
    UMockdevIoctlBase *ioh;
    urb_t q[MAX_URBS], gone[MAX_URBS]; /* pending, and discarded awaiting reap */
    int nq, ngone;
    int armed;
    uint32_t period_us;
    double t0;    /* arming time, ms */
    long made;    /* triggers generated since arming (sent or skipped) */
    long sent;    /* packets sent since start (the fault counters) */
    int gone_dev; /* unplugged: every ioctl fails with ENODEV */
    int pull;     /* main loop: remove the device now */
    double unplug_at;
    int pulled_once; /* the unplug fault happens once */
    int devnum;      /* 3 at the first plug */
    char node[64];
} U = {.period_us = 10000, .devnum = 2};

static struct usbdevfs_urb *U_(urb_t *u)
{
    return (struct usbdevfs_urb *)u->urb->data;
}

static void drop_urb(urb_t *u)
{
    if (u->buf)
        g_object_unref(u->buf);
    g_object_unref(u->urb);
    memset(u, 0, sizeof *u);
}

static int in_list(const int *a, int n, long v)
{
    for (int i = 0; i < n; i++)
        if (a[i] == v)
            return 1;
    return 0;
}

/* The reply to a control request: bytes into data (IN) or the request
 * taken (OUT); -EPIPE (a stall) for anything the box does not know. */
static int control(const uint8_t *setup, uint8_t *data, int room)
{
    uint8_t rt = setup[0], req = setup[1];
    int val = setup[2] | setup[3] << 8, len = setup[6] | setup[7] << 8;
    uint8_t out[255];
    int n = -1;
    if (len > room)
        len = room;
    if (rt == 0x80 && req == 6) { /* GET_DESCRIPTOR */
        int type = val >> 8, idx = val & 0xff;
        if (type == 1) {
            memcpy(out, dev_desc, n = sizeof dev_desc);
        } else if (type == 2) {
            memcpy(out, cfg_desc, n = sizeof cfg_desc);
        } else if (type == 3 && idx == 0) {
            const uint8_t lang[4] = {4, 3, 0x09, 0x04};
            memcpy(out, lang, n = 4);
        } else if (type == 3 && idx < 4) {
            const char *s = strings[idx];
            n = 2 + 2 * (int)strlen(s);
            out[0] = (uint8_t)n;
            out[1] = 3;
            for (size_t i = 0; s[i]; i++)
                out[2 + 2 * i] = (uint8_t)s[i], out[3 + 2 * i] = 0;
        }
    } else if (rt == 0x00 && (req == 9 || req == 11)) { /* SET_CONFIGURATION, SET_INTERFACE */
        n = 0;
    } else if (rt == TRIG_RT_IN && req == TRIG_REQ_IDENT) {
        memset(out, 0, TRIG_IDENT_LEN);
        memcpy(out, TRIG_MAGIC, 4);
        out[4] = 1; /* protocol */
        out[5] = 1, out[6] = 2, out[7] = 3;
        for (int i = 0; i < 4; i++)
            out[8 + i] = (uint8_t)(SERIAL_NO >> (8 * i));
        out[12] = 2;
        n = TRIG_IDENT_LEN;
    } else if (rt == TRIG_RT_IN && req == TRIG_REQ_STATUS) {
        memset(out, 0, TRIG_STATUS_LEN);
        out[0] = (uint8_t)U.armed;
        for (int i = 0; i < 4; i++)
            out[2 + i] = (uint8_t)(U.period_us >> (8 * i));
        n = TRIG_STATUS_LEN;
    } else if (rt == TRIG_RT_OUT && req == TRIG_REQ_PERIOD && len == 4) {
        uint32_t p = (uint32_t)data[0] | (uint32_t)data[1] << 8 | (uint32_t)data[2] << 16 |
                     (uint32_t)data[3] << 24;
        if (p < TRIG_MIN_PERIOD || p > TRIG_MAX_PERIOD)
            return -EPIPE;
        U.period_us = p;
        sim_log("usb: period %u us", p);
        return 4;
    } else if (rt == TRIG_RT_OUT && req == TRIG_REQ_ARM && len == 0) {
        U.armed = val != 0;
        U.t0 = sim_now_ms();
        U.made = 0;
        sim_log("usb: %s", U.armed ? "armed" : "disarmed");
        return 0;
    }
    if (n < 0)
        return -EPIPE;
    if ((rt & 0x80) == 0)
        return 0;
    if (n > len)
        n = len;
    memcpy(data, out, (size_t)n);
    return n;
}

/* Fill a pending bulk IN URB with the triggers due by now; 0 if none. */
static int fill_bulk_in(urb_t *u)
{
    struct usbdevfs_urb *r = U_(u);
    const sim_usb_cfg_t *c = U.cfg;
    if (!U.armed || !u->buf || U.gone_dev)
        return 0;
    if (c->silent_after && U.sent >= c->silent_after)
        return 0;
    long due = (long)((sim_now_ms() - U.t0) * 1000.0 / U.period_us) + 1;
    int room = r->buffer_length / TRIG_PKT_LEN, n = 0;
    while (U.made < due && n < room) {
        long k = U.made++; /* trigger number since arming */
        if (in_list(c->skip, c->nskip, U.sent + 1)) {
            U.sent++; /* counted as sent, never on the wire: a gap */
            sim_log("usb: trigger %ld skipped", k);
            continue;
        }
        hal_trig_pkt_t p = {.flags = 0,
                            .seq = (uint16_t)k,
                            .t_us = (uint32_t)(k * (long)U.period_us),
                            .enc = {(int32_t)(100 * k), (int32_t)(1000 - 3 * k)}};
        uint8_t *w = u->buf->data + n * TRIG_PKT_LEN;
        hal_trig_encode(&p, w);
        U.sent++;
        if (in_list(c->badcrc, c->nbadcrc, U.sent)) {
            w[16] ^= 0x5A;
            sim_log("usb: packet %ld with a bad CRC", U.sent);
        }
        n++;
        if ((c->silent_after && U.sent >= c->silent_after) ||
            (c->unplug_after && U.sent >= c->unplug_after && !U.pulled_once))
            break;
    }
    if (!n)
        return 0;
    r->actual_length = n * TRIG_PKT_LEN;
    r->status = 0;
    if (c->unplug_after && U.sent >= c->unplug_after && !U.pulled_once) {
        U.gone_dev = 1; /* this transfer still arrives; then the box is gone */
        U.pulled_once = 1;
        U.pull = 1;
    }
    return 1;
}

static void submit(UMockdevIoctlClient *client, UMockdevIoctlData *arg)
{
    GError *err = NULL;
    UMockdevIoctlData *d = umockdev_ioctl_data_resolve(arg, 0, sizeof(struct usbdevfs_urb), &err);
    if (!d || U.nq >= MAX_URBS) {
        g_clear_error(&err);
        if (d)
            g_object_unref(d);
        umockdev_ioctl_client_complete(client, -1, d ? ENOMEM : EFAULT);
        return;
    }
    urb_t *u = &U.q[U.nq];
    memset(u, 0, sizeof *u);
    u->urb = d;
    u->addr = d->client_addr; /* arg->data now points at our copy */
    struct usbdevfs_urb *r = U_(u);
    if (r->buffer_length > 0)
        u->buf = umockdev_ioctl_data_resolve(d, offsetof(struct usbdevfs_urb, buffer),
                                             (gsize)r->buffer_length, &err);
    g_clear_error(&err);
    r->actual_length = 0;
    r->status = 0;
    if (r->type == USBDEVFS_URB_TYPE_CONTROL) {
        if (!u->buf || r->buffer_length < 8) {
            r->status = -EINVAL;
        } else {
            int n = control(u->buf->data, u->buf->data + 8, r->buffer_length - 8);
            if (n < 0)
                r->status = n;
            else
                r->actual_length = n; /* the data stage, not the setup packet */
            sim_log("usb: control rt 0x%02x req 0x%02x -> %d", u->buf->data[0], u->buf->data[1], n);
        }
        u->ready = 1;
    } else if (r->type == USBDEVFS_URB_TYPE_BULK && !(r->endpoint & 0x80)) {
        r->actual_length = r->buffer_length; /* bulk OUT: taken */
        u->ready = 1;
    } else if (r->type != USBDEVFS_URB_TYPE_BULK || r->endpoint != TRIG_EP_IN) {
        drop_urb(u);
        umockdev_ioctl_client_complete(client, -1, EINVAL);
        return;
    }
    U.nq++;
    umockdev_ioctl_client_complete(client, 0, 0);
}

static void reap(UMockdevIoctlClient *client, UMockdevIoctlData *arg)
{
    GError *err = NULL;
    urb_t done = {0};
    if (U.ngone) {
        done = U.gone[0];
        memmove(U.gone, U.gone + 1, (size_t)--U.ngone * sizeof U.gone[0]);
        U_(&done)->status = -ENOENT;
        U_(&done)->actual_length = 0;
    } else {
        for (int i = 0; i < U.nq; i++) {
            if (U.q[i].ready || fill_bulk_in(&U.q[i])) {
                done = U.q[i];
                memmove(U.q + i, U.q + i + 1, (size_t)(U.nq - i - 1) * sizeof U.q[0]);
                U.nq--;
                break;
            }
        }
    }
    if (!done.urb) {
        umockdev_ioctl_client_complete(client, -1, EAGAIN);
        return;
    }
    /* The client's void * now points at its own URB, with our changes. */
    UMockdevIoctlData *p = umockdev_ioctl_data_resolve(arg, 0, sizeof(void *), &err);
    g_clear_error(&err);
    if (!p || !umockdev_ioctl_data_set_ptr(p, 0, done.urb)) {
        if (p)
            g_object_unref(p);
        drop_urb(&done);
        umockdev_ioctl_client_complete(client, -1, EFAULT);
        return;
    }
    g_object_unref(p);
    umockdev_ioctl_client_complete(client, 0, 0);
    drop_urb(&done);
}

static void discard(UMockdevIoctlClient *client, UMockdevIoctlData *arg)
{
    gulong addr;
    memcpy(&addr, arg->data, sizeof addr);
    for (int i = 0; i < U.nq; i++) {
        if (U.q[i].addr == addr && U.ngone < MAX_URBS) {
            U.gone[U.ngone++] = U.q[i];
            memmove(U.q + i, U.q + i + 1, (size_t)(U.nq - i - 1) * sizeof U.q[0]);
            U.nq--;
            umockdev_ioctl_client_complete(client, 0, 0);
            return;
        }
    }
    umockdev_ioctl_client_complete(client, -1, EINVAL);
}

static gboolean on_ioctl(UMockdevIoctlBase *base, UMockdevIoctlClient *client, gpointer data)
{
    (void)base;
    (void)data;
    gulong req = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    GError *err = NULL;
    g_mutex_lock(&U.lock);
    if (U.gone_dev && req != (gulong)USBDEVFS_REAPURBNDELAY && req != (gulong)USBDEVFS_REAPURB &&
        req != (gulong)USBDEVFS_DISCARDURB) {
        umockdev_ioctl_client_complete(client, -1, ENODEV);
    } else if (req == (gulong)USBDEVFS_SUBMITURB) {
        submit(client, arg);
    } else if (req == (gulong)USBDEVFS_REAPURBNDELAY || req == (gulong)USBDEVFS_REAPURB) {
        /* After an unplug the URBs already done still reap, then ENODEV. */
        int any = U.ngone > 0;
        for (int i = 0; i < U.nq; i++)
            any |= U.q[i].ready;
        if (U.gone_dev && !any)
            umockdev_ioctl_client_complete(client, -1, ENODEV);
        else
            reap(client, arg);
    } else if (req == (gulong)USBDEVFS_DISCARDURB) {
        discard(client, arg);
    } else if (req == (gulong)USBDEVFS_GET_CAPABILITIES) {
        UMockdevIoctlData *d = umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), &err);
        g_clear_error(&err);
        guint32 caps = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                       USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
        if (d) {
            memcpy(d->data, &caps, sizeof caps);
            g_object_unref(d);
        }
        umockdev_ioctl_client_complete(client, d ? 0 : -1, d ? 0 : EFAULT);
    } else if (req == (gulong)USBDEVFS_CLAIMINTERFACE || req == (gulong)USBDEVFS_RELEASEINTERFACE ||
               req == (gulong)USBDEVFS_SETINTERFACE || req == (gulong)USBDEVFS_SETCONFIGURATION ||
               req == (gulong)USBDEVFS_CLEAR_HALT || req == (gulong)USBDEVFS_RESETEP ||
               req == (gulong)USBDEVFS_RESET) {
        umockdev_ioctl_client_complete(client, 0, 0);
    } else if (req == (gulong)USBDEVFS_GETDRIVER || req == (gulong)USBDEVFS_IOCTL) {
        umockdev_ioctl_client_complete(client, -1, ENODATA); /* no kernel driver bound */
    } else {
        sim_log("usb: ioctl 0x%lx not served", (unsigned long)req);
        umockdev_ioctl_client_complete(client, -1, ENOTTY);
    }
    g_mutex_unlock(&U.lock);
    return TRUE;
}

static int plug(char *msg, size_t len)
{
    GError *err = NULL;
    char desc[2048];
    U.devnum++;
    snprintf(desc, sizeof desc, desc_fmt, U.devnum);
    snprintf(U.node, sizeof U.node, "/dev/bus/usb/001/%03d", U.devnum);
    if (!umockdev_testbed_add_from_string(U.tb, desc, &err)) {
        snprintf(msg, len, "trigger box: %s", err ? err->message : "add_from_string failed");
        g_clear_error(&err);
        return -1;
    }
    U.ioh = umockdev_ioctl_base_new();
    g_signal_connect(U.ioh, "handle-ioctl", G_CALLBACK(on_ioctl), NULL);
    if (!umockdev_testbed_attach_ioctl(U.tb, U.node, U.ioh, &err)) {
        snprintf(msg, len, "trigger box: attach ioctl: %s", err ? err->message : "failed");
        g_clear_error(&err);
        return -1;
    }
    U.gone_dev = 0;
    U.armed = 0;
    sim_log("usb: trigger box 1209:cf01 plugged at %s", U.node);
    return 0;
}

int sim_usb_start(UMockdevTestbed *tb, const sim_usb_cfg_t *cfg, char *msg, size_t len)
{
    g_mutex_init(&U.lock);
    U.tb = tb;
    U.cfg = cfg;
    return plug(msg, len);
}

void sim_usb_tick(void)
{
    if (!U.cfg)
        return;
    g_mutex_lock(&U.lock);
    int pull = U.pull, replug = 0;
    U.pull = 0;
    if (pull)
        U.unplug_at = sim_now_ms();
    if (U.gone_dev && !pull && U.cfg->replug_ms > 0 && U.unplug_at > 0 &&
        sim_now_ms() - U.unplug_at >= U.cfg->replug_ms)
        replug = 1;
    g_mutex_unlock(&U.lock);
    if (pull) {
        GError *err = NULL;
        sim_log("usb: trigger box pulled after %ld packets", U.sent);
        umockdev_testbed_remove_device(U.tb, "/sys" USBDEV "/1-2:1.0");
        umockdev_testbed_remove_device(U.tb, "/sys" USBDEV);
        umockdev_testbed_detach_ioctl(U.tb, U.node, &err);
        g_clear_error(&err);
    }
    if (replug) {
        char msg[256];
        g_mutex_lock(&U.lock);
        U.unplug_at = 0;
        for (int i = 0; i < U.nq; i++)
            drop_urb(&U.q[i]);
        for (int i = 0; i < U.ngone; i++)
            drop_urb(&U.gone[i]);
        U.nq = U.ngone = 0;
        g_mutex_unlock(&U.lock);
        /* No uevents: umockdev 0.17's sender fails on them here; libusb
         * finds the box again by a fresh scan (hal_usb.c). */
        if (plug(msg, sizeof msg))
            fprintf(stderr, "sim-umock: replug: %s\n", msg);
    }
}
