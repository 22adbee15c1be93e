// Prints what libsdformat (Gazebo's URDF -> SDF converter) makes of a URDF file:
//   link <name> <mass>
//   joint <name> <type> <parent> <child>
// then "errors <n>". Built and run by test_sdformat.py; takes the file as its argument.
#include <iomanip>
#include <iostream>
#include <sdf/sdf.hh>

int main(int argc, char **argv)
{
  if (argc != 2) {
    std::cerr << "usage: sdformat_model FILE.urdf" << std::endl;
    return 2;
  }
  sdf::Root root;
  const sdf::Errors errors = root.Load(argv[1]);
  for (const auto &error : errors) {
    std::cerr << error.Message() << std::endl;
  }
#if SDF_MAJOR_VERSION >= 11
  const sdf::Model *model = root.Model();  // sdformat 12 (Debian 12)
#else
  const sdf::Model *model = root.ModelCount() > 0 ? root.ModelByIndex(0) : nullptr;  // sdformat 9 (Noetic)
#endif
  if (model != nullptr) {
    std::cout << std::setprecision(12);
    for (uint64_t i = 0; i < model->LinkCount(); ++i) {
      const sdf::Link *link = model->LinkByIndex(i);
      std::cout << "link " << link->Name() << " " << link->Inertial().MassMatrix().Mass() << "\n";
    }
    for (uint64_t i = 0; i < model->JointCount(); ++i) {
      const sdf::Joint *joint = model->JointByIndex(i);
      std::cout << "joint " << joint->Name() << " " << static_cast<int>(joint->Type()) << " "
                << joint->ParentLinkName() << " " << joint->ChildLinkName() << "\n";
    }
  }
  std::cout << "errors " << errors.size() << std::endl;
  return model != nullptr && errors.empty() ? 0 : 1;
}
