// Depth only: the map is the depth attachment.
void main() {
}
