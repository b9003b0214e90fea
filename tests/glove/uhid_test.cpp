#include <cstdio>
int main() { return 77; }
