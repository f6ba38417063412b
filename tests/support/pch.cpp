// Carries the test executables' shared precompiled header.
