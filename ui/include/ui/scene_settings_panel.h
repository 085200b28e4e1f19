// SceneSettingsPanel: every scene-wide field in one form - the clip's start and end, gravity, the
// ground, the objective's weights, the transcription's starting resolution and the solver's
// settings - each edit one undo command like any other (PropertyForm). Before it, a new scene was
// fixed at a one-second clip under Earth gravity unless its JSON was edited by hand.
#pragma once

#include <QWidget>

#include "ui/document.h"
#include "ui/property_form.h"

namespace spacetime::ui {

class SceneSettingsPanel : public QWidget {
  Q_OBJECT
 public:
  explicit SceneSettingsPanel(Document* doc, QWidget* parent = nullptr);
  PropertyForm* form() { return form_; }

 private:
  Document* doc_;
  PropertyForm* form_;
};

}  // namespace spacetime::ui
