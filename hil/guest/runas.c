/*
 * runas - drops root for the daemon as systemd's User=/Group= would: no supplementary
 * groups, then the group id, then the user id, then exec.
 *
 *   runas UID GID PROGRAM [ARGS...]
 *
 * Build: gcc -static -O2 -Wall -o runas runas.c
 */
#define _GNU_SOURCE
#include <grp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <unistd.h>

int main(int argc, char **argv)
{
	if (argc < 4) {
		fprintf(stderr, "usage: runas UID GID PROGRAM [ARGS...]\n");
		return 2;
	}
	uid_t uid = (uid_t)atoi(argv[1]);
	gid_t gid = (gid_t)atoi(argv[2]);
	if (setgroups(0, NULL) != 0 || setgid(gid) != 0 || setuid(uid) != 0) {
		fprintf(stderr, "runas: cannot become %u:%u: %s\n", uid, gid, strerror(errno));
		return 1;
	}
	execv(argv[3], argv + 3);
	fprintf(stderr, "runas: exec %s: %s\n", argv[3], strerror(errno));
	return 127;
}
