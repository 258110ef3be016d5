/* Small file-path helpers shared by the output writers. Each returns a malloc'ed string (NULL
 * when out of memory) or an errno value; the callers word their own messages. */
#ifndef MPM_PATH_H
#define MPM_PATH_H

/* "dir/name". */
char *mpm_path_join(const char *dir, const char *name);

/* The folder that holds path: "." for a bare name, "/" for a file in the root. */
char *mpm_path_parent(const char *path);

/* The absolute path dir names once mpm_path_make_dir has made it: the folders that exist
 * resolved as the kernel does (links, "..", "."), the rest of the path taken as written
 * ("x/.." is the folder holding x, as for mkdir -p). */
char *mpm_path_resolve(const char *dir);

/* mkdir -p, then check that dir is a folder this process can write into: 0 or an errno. */
int mpm_path_make_dir(const char *dir);

#endif
