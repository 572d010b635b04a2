// The dashboard's area survey: its panel on the map (issue 17).
export { SurveyPanel } from "./panel";
import "./survey.css";
