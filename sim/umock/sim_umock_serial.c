/* SPDX-License-Identifier: MIT */
/* sim_umock_serial.c: the FTDI 0403:6001 adapter at /dev/ttyUSB0 with the
 * laser probe behind it. The testbed's pty master plays the probe's ASCII
 * protocol (M0 -> M0,+01.234 / ER,M0,nn / M0,FFFFFFF; RG -> RG,-50.000,+50.000,
 * the measuring range); an ioctl handler answers the modem-line ioctls a
 * pty lacks (libserialport's sp_open needs TIOCMGET) and passes every
 * other ioctl to the pty. */
#include "sim_umock.h"
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#define USBDEV "/devices/pci0000:00/0000:00:14.0/usb1/1-1"

/* Device, interface, usb-serial port and tty, as the kernel lays them out
 * (libserialport walks tty/ttyUSB0/device/../.. up to idVendor). */
static const char desc[] = "P: " USBDEV "\n"
                           "N: bus/usb/001/002\n"
                           "E: SUBSYSTEM=usb\n"
                           "E: DEVNAME=/dev/bus/usb/001/002\n"
                           "E: DEVTYPE=usb_device\n"
                           "E: DRIVER=usb\n"
                           "E: BUSNUM=001\n"
                           "E: DEVNUM=002\n"
                           "E: ID_VENDOR_ID=0403\n"
                           "E: ID_MODEL_ID=6001\n"
                           "A: busnum=1\n"
                           "A: devnum=2\n"
                           "A: idVendor=0403\n"
                           "A: idProduct=6001\n"
                           "A: manufacturer=FTDI\n"
                           "A: product=FT232R USB UART\n"
                           "A: serial=CFPROBE1\n"
                           "A: speed=12\n"
                           "A: bConfigurationValue=1\n"
                           "A: bNumInterfaces= 1\n"
                           "A: dev=189:1\n"
                           "H: descriptors=12010002000000080304016000060102030109022000010100A02D"
                           "0904000002FFFFFF020705810240000007050202400000\n"
                           "\n"
                           "P: " USBDEV "/1-1:1.0\n"
                           "E: SUBSYSTEM=usb\n"
                           "E: DEVTYPE=usb_interface\n"
                           "E: DRIVER=ftdi_sio\n"
                           "A: bInterfaceNumber=00\n"
                           "A: bInterfaceClass=ff\n"
                           "\n"
                           "P: " USBDEV "/1-1:1.0/ttyUSB0\n"
                           "E: SUBSYSTEM=usb-serial\n"
                           "E: DRIVER=ftdi_sio\n"
                           "A: port_number=0\n"
                           "\n"
                           "P: " USBDEV "/1-1:1.0/ttyUSB0/tty/ttyUSB0\n"
                           "N: ttyUSB0\n"
                           "E: SUBSYSTEM=tty\n"
                           "E: DEVNAME=/dev/ttyUSB0\n"
                           "E: MAJOR=188\n"
                           "E: MINOR=0\n"
                           "A: dev=188:0\n"
                           "L: device=../../../ttyUSB0\n";

static struct {
    UMockdevTestbed *tb;
    const sim_serial_cfg_t *cfg;
    UMockdevIoctlBase *ioh;
    int master;  /* -1 while unplugged */
    int modem;   /* TIOCM_* bits the host set or reads */
    int replies; /* M0 replies sent */
    int pulled;
    char line[256];
    size_t nline;
} S = {.master = -1};

static int in_list(const int *a, int n, int v)
{
    for (int i = 0; i < n; i++)
        if (a[i] == v)
            return 1;
    return 0;
}

/* TIOCM* on the tty: kept here, since a pty has no modem lines. */
static gboolean on_ioctl(UMockdevIoctlBase *base, UMockdevIoctlClient *client, gpointer data)
{
    (void)base;
    (void)data;
    gulong req = umockdev_ioctl_client_get_request(client);
    GError *err = NULL;
    if (req == (gulong)TIOCMGET || req == (gulong)TIOCMSET || req == (gulong)TIOCMBIS ||
        req == (gulong)TIOCMBIC) {
        UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
        UMockdevIoctlData *d = umockdev_ioctl_data_resolve(arg, 0, sizeof(int), &err);
        if (!d) {
            sim_log("serial: cannot read the ioctl argument: %s", err ? err->message : "?");
            g_clear_error(&err);
            umockdev_ioctl_client_complete(client, -1, EFAULT);
            return TRUE;
        }
        int v;
        memcpy(&v, d->data, sizeof v);
        if (req == (gulong)TIOCMGET)
            memcpy(d->data, &S.modem, sizeof S.modem);
        else if (req == (gulong)TIOCMSET)
            S.modem = v;
        else if (req == (gulong)TIOCMBIS)
            S.modem |= v;
        else
            S.modem &= ~v;
        g_object_unref(d);
        umockdev_ioctl_client_complete(client, 0, 0);
        return TRUE;
    }
    if (S.pulled) {
        umockdev_ioctl_client_complete(client, -1, EIO);
        return TRUE;
    }
    int e = 0;
    int r = umockdev_ioctl_client_execute(client, &e, &err);
    if (err) {
        sim_log("serial: ioctl 0x%lx pass-through: %s", (unsigned long)req, err->message);
        g_clear_error(&err);
        r = -1;
        e = EIO;
    }
    umockdev_ioctl_client_complete(client, r, r < 0 ? e : 0);
    return TRUE;
}

static int plug(char *msg, size_t len)
{
    GError *err = NULL;
    if (!umockdev_testbed_add_from_string(S.tb, desc, &err)) {
        snprintf(msg, len, "serial adapter: %s", err ? err->message : "add_from_string failed");
        g_clear_error(&err);
        return -1;
    }
    S.master = umockdev_testbed_get_dev_fd(S.tb, "/dev/ttyUSB0");
    if (S.master < 0) {
        snprintf(msg, len, "serial adapter: no pty behind /dev/ttyUSB0");
        return -1;
    }
    /* The slave side raw (termios on a master reaches the slave): no echo,
     * no line editing, until the host program sets its own mode. */
    struct termios t;
    if (tcgetattr(S.master, &t) == 0) {
        cfmakeraw(&t);
        tcsetattr(S.master, TCSANOW, &t);
    }
    S.ioh = umockdev_ioctl_base_new();
    g_signal_connect(S.ioh, "handle-ioctl", G_CALLBACK(on_ioctl), NULL);
    if (!umockdev_testbed_attach_ioctl(S.tb, "/dev/ttyUSB0", S.ioh, &err)) {
        snprintf(msg, len, "serial adapter: attach ioctl: %s", err ? err->message : "failed");
        g_clear_error(&err);
        return -1;
    }
    S.modem = TIOCM_DSR | TIOCM_CTS | TIOCM_CD;
    S.pulled = 0;
    S.nline = 0;
    sim_log("serial: adapter 0403:6001 plugged, master fd %d", S.master);
    return 0;
}

static void unplug(void)
{
    GError *err = NULL;
    sim_log("serial: adapter pulled after %d replies", S.replies);
    S.pulled = 1;
    umockdev_testbed_detach_ioctl(S.tb, "/dev/ttyUSB0", &err);
    g_clear_error(&err);
    /* Children first: each removal takes its own class and bus links. */
    umockdev_testbed_remove_device(S.tb, "/sys" USBDEV "/1-1:1.0/ttyUSB0/tty/ttyUSB0");
    umockdev_testbed_remove_device(S.tb, "/sys" USBDEV "/1-1:1.0/ttyUSB0");
    umockdev_testbed_remove_device(S.tb, "/sys" USBDEV "/1-1:1.0");
    umockdev_testbed_remove_device(S.tb, "/sys" USBDEV);
    /* The testbed owns the master; with the device gone its slave reads
     * EOF/EIO, which is what a pulled FTDI cable looks like. */
    S.master = -1;
    if (S.ioh) {
        g_object_unref(S.ioh);
        S.ioh = NULL;
    }
}

int sim_serial_start(UMockdevTestbed *tb, const sim_serial_cfg_t *cfg, char *msg, size_t len)
{
    S.tb = tb;
    S.cfg = cfg;
    return plug(msg, len);
}

static void reply(const char *s)
{
    size_t n = strlen(s), off = 0;
    while (off < n) {
        ssize_t w = write(S.master, s + off, n - off);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return;
        off += (size_t)w;
    }
}

static void command(const char *cmd)
{
    char out[64];
    if (!strcmp(cmd, "RG")) { /* measuring range, as hal_probe.c asks */
        reply("RG,-50.000,+50.000\r\n");
        return;
    }
    if (strcmp(cmd, "M0")) {
        sim_log("serial: unknown command '%s'", cmd);
        snprintf(out, sizeof out, "ER,%.8s,00\r\n", cmd[0] ? cmd : "??");
        reply(out);
        return;
    }
    int k = ++S.replies;
    const sim_serial_cfg_t *c = S.cfg;
    double d = c->table[(k - 1) % c->ntable];
    for (int i = 0; i < c->nerr; i++)
        if (c->errat[i] == k) {
            snprintf(out, sizeof out, "ER,M0,%02d\r\n", c->errcode[i]);
            reply(out);
            sim_log("serial: reply %d: error %02d", k, c->errcode[i]);
            return;
        }
    if (isnan(d))
        snprintf(out, sizeof out, "M0,FFFFFFF\r\n");
    else
        snprintf(out, sizeof out, "M0,%+07.3f\r\n", d);
    if (in_list(c->garble, c->ngarble, k)) {
        /* Line noise: bits flipped in the value, the line ending intact. */
        size_t end = strcspn(out, "\r");
        for (size_t i = 3; i < end; i += 2)
            out[i] ^= 0x40; /* printable, never a line end */
        sim_log("serial: reply %d garbled", k);
    }
    reply(out);
    sim_log("serial: reply %d: %.*s", k, (int)strcspn(out, "\r"), out);
}

void sim_serial_tick(void)
{
    if (!S.cfg)
        return;
    if (S.pulled)
        return;
    struct pollfd p = {S.master, POLLIN, 0};
    while (poll(&p, 1, 0) == 1 && (p.revents & POLLIN)) {
        char buf[256];
        ssize_t n = read(S.master, buf, sizeof buf);
        if (n <= 0)
            return; /* no slave open (EIO): nothing to serve */
        for (ssize_t i = 0; i < n; i++) {
            char ch = buf[i];
            if (ch == '\r' || ch == '\n') {
                if (!S.nline)
                    continue;
                S.line[S.nline] = 0;
                S.nline = 0;
                command(S.line);
                if (S.cfg->unplug_after && S.replies >= S.cfg->unplug_after) {
                    unplug();
                    return;
                }
            } else if (S.nline + 1 < sizeof S.line) {
                S.line[S.nline++] = ch;
            }
        }
    }
}
