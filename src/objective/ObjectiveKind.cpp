#include "objective/ObjectiveKind.h"

#include "core/Registry.h"

namespace sl {

namespace {

constexpr ObjectiveKindRow kKinds[] = {
    {ObjectiveKind::Paper, "paper", "the paper's eq. 2 on one estimate of T (rewards noise)", 1},
    {ObjectiveKind::Unbiased, "unbiased",
     "products of differences of two independent half-sample images (noise-unbiased)", 2},
    {ObjectiveKind::Defects, "defects",
     "the defects' gradient over the defect-free surface's (noise-unbiased), kept exposed; "
     "needs a defect mask",
     2},
};

constexpr DefectMeasureRow kMeasures[] = {
    {DefectMeasure::Ratio, "ratio", "the defects' RMS gradient over the defect-free surface's"},
    {DefectMeasure::Jnd, "jnd",
     "the defects' visibility in just-noticeable differences (the judge's first figure)"},
    {DefectMeasure::Both, "both",
     "the worse of the two measures' gains over the user's lamp: seen more in JND and standing "
     "out of the texture more"},
};

}  // namespace

std::span<const ObjectiveKindRow> objectiveKindTable() {
    return kKinds;
}

ObjectiveKind parseObjectiveKind(std::string_view name, const std::string& where) {
    return parseRegistryName(objectiveKindTable(), name, where).value;
}

const char* objectiveKindName(ObjectiveKind kind) {
    return registryRow(objectiveKindTable(), kind).name;
}

std::span<const DefectMeasureRow> defectMeasureTable() {
    return kMeasures;
}

DefectMeasure parseDefectMeasure(std::string_view name, const std::string& where) {
    return parseRegistryName(defectMeasureTable(), name, where).value;
}

const char* defectMeasureName(DefectMeasure measure) {
    return registryRow(defectMeasureTable(), measure).name;
}

}  // namespace sl
