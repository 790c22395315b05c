// The objectives the optimizers minimize: one table (core/Registry.h), the only list of them.
//   paper     the paper's eq. 2 on one estimate of T (objective/Objective.h ImageObjective):
//             its |ΔI| terms include the noise of the estimate, so it rewards noise
//   unbiased  products of differences of two independent half-sample images
//             (objective/UnbiasedObjective.h): an unbiased estimate of the noise-free eq.-2
//             gradient term; needs T's two halves
//   defects   the defect region's gradient energy over the defect-free surface's, unbiased,
//             with an exposure band (objective/DefectObjective.h); needs the halves and a
//             defect mask
#pragma once

#include <span>
#include <string>
#include <string_view>

namespace sl {

enum class ObjectiveKind { Paper, Unbiased, Defects };

/// What the defects objective makes large (its second table):
///   ratio  the defects' RMS gradient over the defect-free surface's (objective/DefectObjective.h)
///   jnd    the defects' visibility in just-noticeable differences, the judge's first figure
///          (objective/JndObjective.h): contrast sensitivity, masking by the texture, luminance
///   both   the worse of the two's gains over the user's lamp (objective/BothMeasuresObjective.h)
enum class DefectMeasure { Ratio, Jnd, Both };

struct ObjectiveKindRow {
    ObjectiveKind value;
    const char* name;
    const char* help;
    int planes;  // sample sets of T it needs (the unbiased objective: two halves)
};

std::span<const ObjectiveKindRow> objectiveKindTable();
/// The kind named `name`; InputError naming `where` and listing the table otherwise.
ObjectiveKind parseObjectiveKind(std::string_view name, const std::string& where = "objective");
const char* objectiveKindName(ObjectiveKind kind);

struct DefectMeasureRow {
    DefectMeasure value;
    const char* name;
    const char* help;
};
std::span<const DefectMeasureRow> defectMeasureTable();
/// The measure named `name`; InputError naming `where` and listing the table otherwise.
DefectMeasure parseDefectMeasure(std::string_view name, const std::string& where = "measure");
const char* defectMeasureName(DefectMeasure measure);

}  // namespace sl
