// Stands in for an engine: loads the shader iqc generated at build time and prints its size and first line.
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

int main() {
    std::ifstream in(SHADER_PATH);
    if (!in) {
        std::cerr << "viewer: cannot read " << SHADER_PATH << "\n";
        return 1;
    }
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::cout << "viewer: " << text.size() << " bytes, " << text.substr(0, text.find('\n')) << "\n";
    return 0;
}
