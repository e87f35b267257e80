// Placeholder until the demo lands (foundation issue).
#include <cstdio>
int main() { std::puts("cullkit demo: not yet"); return 0; }
