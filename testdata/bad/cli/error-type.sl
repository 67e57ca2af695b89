shader s(float k = 1) {
    color c = P;
    Ci = c;
}
