/*
 * hil-udevd - the guest's stand-in for systemd-udevd, applying what
 * udev/70-crowdtouch.rules says, so the daemon meets device nodes the way it does on
 * a kiosk: created by the kernel as root 0600, then given the rule's group and mode,
 * then announced in udev's database (/run/udev/data/c<major>:<minor>), in that order.
 *
 *   touchscreen event nodes (INPUT_PROP_DIRECT and ABS_MT_POSITION_X/Y or ABS_X/Y):
 *       group EV_GROUP, mode EV_MODE                 (ENV{ID_INPUT_TOUCHSCREEN}=="1")
 *   hidraw nodes whose HID device is bound to hid-multitouch:
 *       group HID_GROUP, mode HID_MODE               (DRIVERS=="hid-multitouch")
 *
 * The values come from the command line, which the host harness reads out of the rule
 * file. While /tmp/hil-deny exists the rule is not applied (the node stays root 0600),
 * for the permission scenario. Every decision is printed as a `UDEV ...` line.
 *
 *   hil-udevd EV_GROUP_ID EV_MODE_OCTAL HID_GROUP_ID HID_MODE_OCTAL
 *
 * Build: gcc -static -O2 -Wall -o hil-udevd hil-udevd.c
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <linux/netlink.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static gid_t ev_gid, hid_gid;
static mode_t ev_mode, hid_mode;

static int read_file(const char *path, char *buf, size_t n)
{
	int fd = open(path, O_RDONLY | O_CLOEXEC);
	if (fd < 0)
		return -1;
	ssize_t r = read(fd, buf, n - 1);
	close(fd);
	if (r < 0)
		return -1;
	buf[r] = 0;
	while (r > 0 && (buf[r - 1] == '\n' || buf[r - 1] == ' '))
		buf[--r] = 0;
	return (int)r;
}

/* Bit `bit` of a sysfs bitmap ("hex words, most significant first, space separated"). */
static int test_bit(const char *bitmap, int bit)
{
	char tmp[1024];
	char *words[64];
	int n = 0;
	snprintf(tmp, sizeof tmp, "%s", bitmap);
	for (char *s = strtok(tmp, " "); s && n < 64; s = strtok(NULL, " "))
		words[n++] = s;
	int w = bit / 64, b = bit % 64;
	if (w >= n)
		return 0;
	unsigned long long v = strtoull(words[n - 1 - w], NULL, 16);
	return (int)((v >> b) & 1);
}

static void sleep_ms(int ms)
{
	struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
	nanosleep(&t, NULL);
}

static void handle(const char *action, const char *devpath, const char *subsystem,
		   const char *devname, const char *major, const char *minor)
{
	char node[256], path[512], buf[1024], facts[1024] = "";
	if (!devname || !major || !minor)
		return;
	if (strcmp(action, "remove") == 0) {
		snprintf(path, sizeof path, "/run/udev/data/c%s:%s", major, minor);
		unlink(path);
		return;
	}
	if (strcmp(action, "add") != 0)
		return;
	int apply = 0;
	gid_t gid = 0;
	mode_t mode = 0600;
	snprintf(node, sizeof node, "/dev/%s", devname);
	if (strcmp(subsystem, "input") == 0 && strncmp(devname, "input/event", 11) == 0) {
		char props[256] = "", abs[1024] = "";
		snprintf(path, sizeof path, "/sys%s/device/properties", devpath);
		read_file(path, props, sizeof props);
		snprintf(path, sizeof path, "/sys%s/device/capabilities/abs", devpath);
		read_file(path, abs, sizeof abs);
		int direct = test_bit(props, 1);
		int mt = test_bit(abs, 0x35) && test_bit(abs, 0x36);
		int st = test_bit(abs, 0x00) && test_bit(abs, 0x01);
		if (direct && (mt || st)) {
			apply = 1;
			gid = ev_gid;
			mode = ev_mode;
			strcat(facts, "E:ID_INPUT=1\nE:ID_INPUT_TOUCHSCREEN=1\n");
		}
	} else if (strcmp(subsystem, "hidraw") == 0) {
		/* The hidraw node is created while hid-multitouch probes; the driver link
		 * appears when the probe returns. udev's DRIVERS== sees the bound driver. */
		snprintf(path, sizeof path, "/sys%s/device/driver", devpath);
		for (int i = 0; i < 100; i++) {
			ssize_t r = readlink(path, buf, sizeof buf - 1);
			if (r > 0) {
				buf[r] = 0;
				const char *d = strrchr(buf, '/');
				if (strcmp(d ? d + 1 : buf, "hid-multitouch") == 0) {
					apply = 1;
					gid = hid_gid;
					mode = hid_mode;
				}
				break;
			}
			sleep_ms(10);
		}
	} else {
		return;
	}
	/* ID_PATH for devices on PCI, as udev's path_id builtin would give it. */
	const char *pci = strstr(devpath, "/pci0000:");
	if (pci) {
		const char *dev = strchr(pci + 1, '/');
		if (dev) {
			char id[64];
			size_t l = strcspn(dev + 1, "/");
			if (l < sizeof id) {
				memcpy(id, dev + 1, l);
				id[l] = 0;
				snprintf(facts + strlen(facts), sizeof facts - strlen(facts), "E:ID_PATH=pci-%s\n", id);
			}
		}
	}
	int denied = access("/tmp/hil-deny", F_OK) == 0;
	if (apply && !denied) {
		if (chown(node, 0, gid) != 0 || chmod(node, mode) != 0)
			printf("UDEV ERR %s: %s\n", node, strerror(errno));
	}
	/* The database record last: its appearance means "udev has processed it". */
	snprintf(path, sizeof path, "/run/udev/data/c%s:%s", major, minor);
	FILE *f = fopen(path, "w");
	if (f) {
		fprintf(f, "%s", facts);
		fclose(f);
	}
	struct stat st;
	stat(node, &st);
	printf("UDEV add %s rule=%s group=%u mode=%04o\n", node,
	       !apply ? "none" : denied ? "denied" : "applied", st.st_gid, st.st_mode & 07777);
	fflush(stdout);
}

int main(int argc, char **argv)
{
	if (argc != 5) {
		fprintf(stderr, "usage: hil-udevd EV_GID EV_MODE HID_GID HID_MODE\n");
		return 2;
	}
	ev_gid = (gid_t)atoi(argv[1]);
	ev_mode = (mode_t)strtol(argv[2], NULL, 8);
	hid_gid = (gid_t)atoi(argv[3]);
	hid_mode = (mode_t)strtol(argv[4], NULL, 8);
	mkdir("/run/udev", 0755);
	mkdir("/run/udev/data", 0755);
	int s = socket(AF_NETLINK, SOCK_DGRAM | SOCK_CLOEXEC, NETLINK_KOBJECT_UEVENT);
	struct sockaddr_nl a = {.nl_family = AF_NETLINK, .nl_groups = 1};
	if (s < 0 || bind(s, (struct sockaddr *)&a, sizeof a) < 0) {
		printf("UDEV ERR netlink: %s\n", strerror(errno));
		return 1;
	}
	int rcv = 4 << 20;
	setsockopt(s, SOL_SOCKET, SO_RCVBUFFORCE, &rcv, sizeof rcv);
	/* udev is "running" from now on: the daemon waits for database records. */
	close(open("/run/udev/control", O_CREAT | O_WRONLY | O_CLOEXEC, 0644));
	printf("UDEV READY\n");
	fflush(stdout);
	static char msg[16384];
	for (;;) {
		ssize_t n = recv(s, msg, sizeof msg - 1, 0);
		if (n <= 0)
			continue;
		msg[n] = 0;
		const char *action = NULL, *devpath = NULL, *subsystem = NULL, *devname = NULL,
			   *major = NULL, *minor = NULL;
		for (char *p = msg + strlen(msg) + 1; p < msg + n; p += strlen(p) + 1) {
			if (!strncmp(p, "ACTION=", 7))
				action = p + 7;
			else if (!strncmp(p, "DEVPATH=", 8))
				devpath = p + 8;
			else if (!strncmp(p, "SUBSYSTEM=", 10))
				subsystem = p + 10;
			else if (!strncmp(p, "DEVNAME=", 8))
				devname = p + 8;
			else if (!strncmp(p, "MAJOR=", 6))
				major = p + 6;
			else if (!strncmp(p, "MINOR=", 6))
				minor = p + 6;
		}
		if (action && devpath && subsystem)
			handle(action, devpath, subsystem, devname, major, minor);
	}
}
