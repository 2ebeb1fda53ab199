/* The supervisors' key file (docs/deploy.md "Signed supervisors"): where
 * landscaped finds it and how it reads it into the core's ls_auth_t.
 *
 * A key file holds one key per line, `NAME = 64 hex digits` (32 bytes), with
 * `#` or `;` comments; NAME is what a supervisor names in its challenge
 * (ConnectReq.key_id). Its home is the [security] key_file of landscaped.conf,
 * or, when that is empty, the systemd credential LS_KEYS_CREDENTIAL
 * (LoadCredential= in landscaped.service: $CREDENTIALS_DIRECTORY), never a
 * command line. Only its owner may read it: a file that grants its group or
 * others any access is refused, naming the chmod that fixes it.
 *
 * No message here ever carries a key's bytes, nor any part of a value.
 * Init-time only (stdio, stat); the caller owns every buffer. */
#ifndef LS_KEYS_H
#define LS_KEYS_H

#include <stddef.h>

#include "ls_auth.h"
#include "ls_config.h"

/* The credential name landscaped.service loads the key file as. */
#define LS_KEYS_CREDENTIAL "landscaped-keys"

/* The key file in effect into buf: [security] key_file, else the
 * credential when $CREDENTIALS_DIRECTORY holds it; NULL when there is none
 * (or the path does not fit buf). */
const char *ls_keys_path(const ls_config_t *cfg, char *buf, size_t buflen);

/* Whether only the file's owner may use it (a regular file, no group or
 * other permission bits): LS_OK, or LS_EPERM / LS_ENODEV (missing) /
 * LS_EINVAL (not a regular file) with msg "PATH: ..." saying what to do. */
int ls_keys_check_mode(const char *path, char *msg, size_t msglen);

/* Read the keys of `path` into `auth` (ls_auth_add_key, after
 * ls_keys_check_mode). LS_OK; LS_EPERM, LS_ENODEV or LS_EIO (the file) or
 * LS_EINVAL (its contents: "PATH:LINE: ...", a bad name, not 64 hex
 * digits, a name given twice, more than LS_AUTH_MAX_KEYS keys, no key at
 * all). The lines read are wiped; on error `auth` may hold the keys read
 * before it (the caller wipes it). */
int ls_keys_load(const char *path, ls_auth_t *auth, char *msg, size_t msglen);

#endif
