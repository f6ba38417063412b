#include <cstdio>
int main() { std::puts("atelier"); return 0; }
