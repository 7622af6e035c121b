"""How the tests build exported C: every warning an error; -O1, which compiles the large
generated files about three times faster than the Makefile's default -O2 (the generated NLP
of an order4 problem is megabytes of C) and runs the small test instances as well."""

CFLAGS = "-O1 -Wall -Wextra -Werror"
