/*
 * sockfwd - the guest's socket client: connects to the crowdtouch daemon's Unix socket
 * once per HELLO argument, sends that hello, and forwards every line the daemon writes
 * to a serial port for the host, stamped with the guest's CLOCK_MONOTONIC at read:
 *
 *   S<conn> <guest_monotonic_us> <the daemon's line>
 *
 * The host compares `guest_monotonic_us` with a snapshot's `input_t_us` (the kernel's
 * timestamp of the touch) to get the daemon's own latency as a client sees it. A
 * connection that closes (daemon restart) is reported and re-established. Lines the
 * host writes to the serial port (commands) go to the first connection.
 *
 *   sockfwd OUT_TTY SOCKET_PATH HELLO_JSON [HELLO_JSON ...]
 *
 * Build: gcc -static -O2 -Wall -o sockfwd sockfwd.c
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define MAX_CONN 4
#define BUF_BYTES (1 << 20)

struct conn {
	int fd;
	const char *hello;
	char *buf;
	size_t len;
};

static int out = -1;

static long long mono_us(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (long long)t.tv_sec * 1000000 + t.tv_nsec / 1000;
}

static void write_all(const char *p, size_t n)
{
	while (n > 0) {
		ssize_t w = write(out, p, n);
		if (w < 0) {
			if (errno == EINTR || errno == EAGAIN)
				continue;
			return;
		}
		p += w;
		n -= (size_t)w;
	}
}

static void say(const char *fmt, int i, const char *what)
{
	char line[512];
	int n = snprintf(line, sizeof line, fmt, i, what);
	if (n > 0)
		write_all(line, (size_t)n < sizeof line ? (size_t)n : sizeof line - 1);
}

static int try_connect(const char *path)
{
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
	struct sockaddr_un a;
	memset(&a, 0, sizeof a);
	a.sun_family = AF_UNIX;
	snprintf(a.sun_path, sizeof a.sun_path, "%s", path);
	if (fd < 0)
		return -1;
	if (connect(fd, (struct sockaddr *)&a, sizeof a) < 0) {
		close(fd);
		return -1;
	}
	return fd;
}

int main(int argc, char **argv)
{
	if (argc < 4 || argc - 3 > MAX_CONN) {
		fprintf(stderr, "usage: sockfwd OUT_TTY SOCKET HELLO [HELLO ...] (at most %d)\n", MAX_CONN);
		return 2;
	}
	out = open(argv[1], O_RDWR | O_NOCTTY);
	if (out < 0) {
		fprintf(stderr, "sockfwd: open %s: %s\n", argv[1], strerror(errno));
		return 1;
	}
	struct termios t;
	if (tcgetattr(out, &t) == 0) {
		cfmakeraw(&t);
		cfsetspeed(&t, B115200); /* QEMU's UART does not throttle to the baud rate */
		tcsetattr(out, TCSANOW, &t);
	}
	const char *path = argv[2];
	int n = argc - 3;
	struct conn c[MAX_CONN];
	for (int i = 0; i < n; i++) {
		c[i].fd = -1;
		c[i].hello = argv[3 + i];
		c[i].buf = malloc(BUF_BYTES);
		c[i].len = 0;
		if (!c[i].buf)
			return 1;
	}
	say("FWD %d READY %s\n", 0, path);
	static char line[BUF_BYTES + 64];
	for (;;) {
		struct pollfd p[MAX_CONN + 1];
		int waiting = 0;
		for (int i = 0; i < n; i++) {
			if (c[i].fd < 0) {
				c[i].fd = try_connect(path);
				if (c[i].fd >= 0) {
					size_t hl = strlen(c[i].hello);
					if (write(c[i].fd, c[i].hello, hl) != (ssize_t)hl || write(c[i].fd, "\n", 1) != 1) {
						close(c[i].fd);
						c[i].fd = -1;
					} else {
						c[i].len = 0;
						say("FWD %d CONNECTED %s\n", i, path);
					}
				}
			}
			if (c[i].fd < 0)
				waiting = 1;
			p[i].fd = c[i].fd;
			p[i].events = POLLIN;
			p[i].revents = 0;
		}
		p[n].fd = out;
		p[n].events = POLLIN;
		p[n].revents = 0;
		if (poll(p, n + 1, waiting ? 20 : -1) < 0 && errno != EINTR)
			return 1;
		if (p[n].revents & POLLIN) {
			/* host -> daemon: passed through unchanged to connection 0 */
			static char in[65536];
			ssize_t r = read(out, in, sizeof in);
			if (r > 0 && c[0].fd >= 0 && write(c[0].fd, in, (size_t)r) != r)
				say("FWD %d SHORT %s\n", 0, "write of a host line");
		}
		for (int i = 0; i < n; i++) {
			if (c[i].fd < 0 || !(p[i].revents & (POLLIN | POLLHUP | POLLERR)))
				continue;
			ssize_t r = read(c[i].fd, c[i].buf + c[i].len, BUF_BYTES - c[i].len);
			long long now = mono_us();
			if (r <= 0) {
				close(c[i].fd);
				c[i].fd = -1;
				say("FWD %d CLOSED %s\n", i, r == 0 ? "eof" : strerror(errno));
				continue;
			}
			c[i].len += (size_t)r;
			char *s = c[i].buf, *end = c[i].buf + c[i].len, *nl;
			while ((nl = memchr(s, '\n', (size_t)(end - s)))) {
				int h = snprintf(line, 64, "S%d %lld ", i, now);
				size_t l = (size_t)(nl - s) + 1;
				memcpy(line + h, s, l);
				write_all(line, (size_t)h + l);
				s = nl + 1;
			}
			c[i].len = (size_t)(end - s);
			memmove(c[i].buf, s, c[i].len);
			if (c[i].len == BUF_BYTES) {
				say("FWD %d OVERLONG %s\n", i, "line dropped");
				c[i].len = 0;
			}
		}
	}
}
