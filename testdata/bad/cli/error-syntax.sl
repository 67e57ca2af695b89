shader s() {
    Ci = (u + ;
}
